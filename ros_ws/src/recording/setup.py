from setuptools import find_packages, setup

package_name = "recording"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="Tug simulator maintainers",
    maintainer_email="maintainer@tugsim.example.org",
    description="A run's MCAP recording (as rosbag2 writes it), its replay and its analysis.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "replay = recording.replay:main",
            "analyze = recording.analysis:main",
        ],
    },
)
