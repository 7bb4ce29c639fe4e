from glob import glob

from setuptools import find_packages, setup

package_name = "rope_model"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        ("share/" + package_name + "/ropes", glob("ropes/*.yaml")),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="Tug simulator maintainers",
    maintainer_email="maintainer@tugsim.example.org",
    description="Towing rope models (multi-body element chain of Yoon, Lee, Park, Kim; finite-difference cable of Park & Jung) and the one rope node that runs any rope file.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "rope_node = rope_model.rope_node:main",
        ],
    },
)
