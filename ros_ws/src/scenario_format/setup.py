from setuptools import find_packages, setup

package_name = "scenario_format"

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
    description="ROS-free description of a run: the scenario format, a run's particulars, units, "
                "geodesy and bridge-equipment identities at the human edge.",
    license="Apache-2.0",
)
