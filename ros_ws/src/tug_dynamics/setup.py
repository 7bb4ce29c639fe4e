from glob import glob

from setuptools import find_packages, setup

package_name = "tug_dynamics"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        ("share/" + package_name + "/ships", glob("ships/*.yaml")),
        # hydrodynamic data of the displacement hulls (scripts/hydro_data.py; tug_dynamics.wave_response)
        ("share/" + package_name + "/ships/hydro", glob("ships/hydro/*.npz")),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="Tug simulator maintainers",
    maintainer_email="maintainer@tugsim.example.org",
    description="Vessel manoeuvring models (Yun & Kim barge, Yoon S-175 with anchor dredging, harbour tug, Yoon & Kang planing hull) and the one vessel node that runs any ship file.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "vessel_node = tug_dynamics.vessel_node:main",
        ],
    },
)
