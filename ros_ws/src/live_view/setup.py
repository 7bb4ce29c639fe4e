from setuptools import find_packages, setup

package_name = "live_view"

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
    description="Live view of a running simulation: a Foxglove WebSocket server (foxglove-sdk) for Foxglove and Lichtblick.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "live_view = live_view.live_view_node:main",
        ],
    },
)
