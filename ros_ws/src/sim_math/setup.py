from setuptools import find_packages, setup

package_name = "sim_math"

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
    description="ROS-free numerics shared by the physics and analysis packages: rotations, RK4, "
                "LU solves, circle fit and the IMO turning measures.",
    license="Apache-2.0",
)
