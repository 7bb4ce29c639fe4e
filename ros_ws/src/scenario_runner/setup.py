from glob import glob

from setuptools import find_packages, setup

package_name = "scenario_runner"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        ("share/" + package_name + "/scenarios", glob("scenarios/*.yaml") + glob("scenarios/*.asc")),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="Tug simulator maintainers",
    maintainer_email="maintainer@tugsim.example.org",
    description="Scenario runner of the towing simulator: validates a scenario file, starts the nodes, owns /clock and the lockstep protocol, records MCAP.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "send_command = scenario_runner.send_command:main",
            "run_scenario = scenario_runner.run_scenario:main",
            "autopilot = scenario_runner.autopilot:main",
            "node_group = scenario_runner.node_group:main",
        ],
    },
)
