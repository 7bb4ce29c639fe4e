from glob import glob

from setuptools import find_packages, setup

package_name = "studies"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        ("share/" + package_name + "/examples", glob("examples/*.yaml")),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="Tug simulator maintainers",
    maintainer_email="maintainer@tugsim.example.org",
    description="Studies: sweeps and Monte Carlo seeds of a scenario on a Dask cluster, their measures in one table, extreme-value statistics.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "study = studies.study:main",
        ],
    },
)
