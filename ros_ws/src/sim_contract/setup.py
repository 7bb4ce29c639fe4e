from setuptools import find_packages, setup

package_name = "sim_contract"

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
    description="The nodes' contract, ROS-free: parameter tables, units and geodesy at the human edge, "
                "bridge-equipment identities.",
    license="Apache-2.0",
)
