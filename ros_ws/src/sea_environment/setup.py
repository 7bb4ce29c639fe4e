from setuptools import find_packages, setup

package_name = "sea_environment"

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
    description="ROS-free models of the environment the vessels and ropes work in: wind (mean profile and "
                "gusts from the NPD / ISO 19901-1 spectrum; Blendermann wind loads), depth and shallow water, currents.",
    license="Apache-2.0",
)
