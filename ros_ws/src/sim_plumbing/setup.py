from setuptools import find_packages, setup

package_name = "sim_plumbing"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        ("share/" + package_name + "/config", ["config/fastdds_discovery.xml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="Tug simulator maintainers",
    maintainer_email="maintainer@tugsim.example.org",
    description="Shared node plumbing of the tug simulator: lockstep step protocol, CDR codecs, recorder feed, ROS helpers.",
    license="Apache-2.0",
)
