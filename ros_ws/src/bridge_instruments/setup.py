from setuptools import find_packages, setup

package_name = "bridge_instruments"

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
    description="NMEA 0183 and AIS out over UDP, and a terminal console to drive one vessel.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "nmea_out = bridge_instruments.nmea_out:main",
            "console = bridge_instruments.console:main",
        ],
    },
)
