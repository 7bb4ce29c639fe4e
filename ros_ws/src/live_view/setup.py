import os

from setuptools import find_packages, setup

package_name = "live_view"

# The instructor station's page, and three.js as scripts/ensure_env.sh installs it (npm ci in web/,
# pinned by web/package-lock.json). Without it (no npm) the page's server says what is missing.
_THREE = {"three.module.js": "web/node_modules/three/build/three.module.js",
          "three.core.js": "web/node_modules/three/build/three.core.js",
          "OrbitControls.js": "web/node_modules/three/examples/jsm/controls/OrbitControls.js",
          "LICENSE": "web/node_modules/three/LICENSE"}
_here = os.path.dirname(os.path.abspath(__file__))
_vendor = [p for p in _THREE.values() if os.path.isfile(os.path.join(_here, p))]

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        ("share/" + package_name + "/web", ["web/index.html", "web/app.js", "web/style.css", "web/package.json",
                                            "web/package-lock.json"]),
    ] + ([("share/" + package_name + "/web/vendor", _vendor)] if _vendor else []),
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="Tug simulator maintainers",
    maintainer_email="maintainer@tugsim.example.org",
    description="Live view of a running simulation: a Foxglove WebSocket server (foxglove-sdk) for Foxglove and "
                "Lichtblick, and the browser instructor station (three.js).",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "live_view = live_view.live_view_node:main",
        ],
    },
)
