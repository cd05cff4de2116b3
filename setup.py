"""Packaging for bsp_ros: an ament_python package that also installs with pip."""

from glob import glob

from setuptools import find_packages, setup

PACKAGE = "bsp_ros"
LIVE = [
    "ros-jazzy-rclpy[fastrtps]",
    "ros-jazzy-geometry-msgs",
    "ros-jazzy-sensor-msgs",
    "ros-jazzy-std-msgs",
    "ros-jazzy-diagnostic-msgs",
    "ros-jazzy-nav-msgs",
    "ros-jazzy-trajectory-msgs",
    "ros-jazzy-std-srvs",
    "ros-jazzy-visualization-msgs",
]
NODES = ["cell_simulator", "joint_angle_estimator", "bsp_identifier", "session_recorder", "arm_visualizer"]

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(include=["bsp_ros", "bsp_ros.*", "msg_adapters", "msg_adapters.*"]),
    package_data={"bsp_ros": ["py.typed", "config/*.yaml"], "msg_adapters": ["py.typed"]},
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE]),
        ("share/" + PACKAGE, ["package.xml"]),
        ("share/" + PACKAGE + "/launch", glob("launch/*.launch.py")),
        ("share/" + PACKAGE + "/config", glob("bsp_ros/config/*.yaml")),
    ],
    python_requires=">=3.10",
    # Every third-party module the package imports, by distribution (test/test_packaging.py checks it).
    # Lower bounds admit what Ubuntu 24.04 (Jazzy's platform) ships from apt: NumPy 1.26, matplotlib 3.6.3.
    install_requires=[
        "numpy>=1.26",
        "scipy>=1.11",
        "pyyaml>=6.0",
        "rosbags>=0.10",
        "mcap>=1.1",
        "mcap-ros2-support>=0.5",
        "lz4>=4.0",
        "zstandard>=0.21",
        "matplotlib>=3.6",
        "threadpoolctl>=3.1",
    ],
    extras_require={
        # Real Jazzy rclpy with Fast DDS and the message packages, from PyPI wheels (Linux x86_64, CPython
        # 3.10-3.13). A cell with apt's ROS 2 Jazzy needs no extra: colcon and rosdep provide them.
        "live": LIVE,
        # pin: pinocchio, the independent rigid-body dynamics the simulator and the regressor are tested against;
        # mujoco: an independent physics-engine cell; opensim (cp311 wheel only): a musculoskeletal arm (test/physics).
        "test": [
            "pytest>=7",
            "ruff",
            "mypy",
            "psycopg[binary]>=3.1",
            "colcon-core",
            "colcon-ros",
            "pin>=3",
            "mujoco",
            'opensim; python_version == "3.11"',
        ],
        "postgres": ["psycopg[binary]>=3.1"],
    },
    zip_safe=True,
    maintainer="bsp_ros developers",
    maintainer_email="dev@bsp-ros.local",
    description="Online identification of arm body segment parameters for rehabilitation robot cells.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": ["bsp = bsp_ros.cli:main"] + [f"{node} = bsp_ros.live.nodes.{node}:main" for node in NODES],
    },
)
