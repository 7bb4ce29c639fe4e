from setuptools import find_packages, setup

package_name = "hull_contact"

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
    description="Contact between a tug's fender and another vessel's hull (pushing): the ROS-free "
                "spring-dashpot-friction model and the node that couples two vessels through it.",
    license="Apache-2.0",
    entry_points={"console_scripts": ["contact_node = hull_contact.contact_node:main",
                                     "interaction_node = hull_contact.interaction_node:main"]},
)
