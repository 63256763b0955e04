"""The ROS 2 package vsinv (colcon, ament_python): installs the launch file, the parameters
file and the ``vsinv_ros`` executable (``ros2 run vsinv vsinv_ros``); the code is the vsinv
Python package, installed with pip."""

from glob import glob

from setuptools import setup

setup(
    name="vsinv",
    version="0.1.0",
    packages=[],
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/vsinv"]),
        ("share/vsinv", ["package.xml"]),
        ("share/vsinv/launch", glob("launch/*.launch.py")),
        ("share/vsinv/config", glob("config/*.yaml")),
    ],
    zip_safe=True,
    entry_points={"console_scripts": ["vsinv_ros = vsinv.ros.__main__:main"]},
)
