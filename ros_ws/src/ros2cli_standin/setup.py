from setuptools import find_packages, setup

package_name = "ros2cli_standin"

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
    description="A stand-in for the ros2cli graph verbs (topic, node, param) that are not on PyPI.",
    license="Apache-2.0",
)
