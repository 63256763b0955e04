"""The ROS 2 package in ros/vsinv (colcon, ament_python): package.xml, the launch file and its
parameters file, checked without ROS (the launch file itself runs only where launch_ros is)."""

from __future__ import annotations

import ast
import importlib.util
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import vsinv
from ros_yaml import flat
from vsinv.ros import parse_parameters

PACKAGE = Path(__file__).resolve().parent.parent / "ros" / "vsinv"


def test_package_xml_names_an_ament_python_package_vsinv() -> None:
    root = ET.parse(PACKAGE / "package.xml").getroot()
    assert root.get("format") == "3" and root.findtext("name") == "vsinv"
    assert root.findtext("export/build_type") == "ament_python"
    depends = {e.text for e in root.findall("exec_depend")}
    assert {"rclpy", "sensor_msgs", "geometry_msgs", "std_srvs", "diagnostic_msgs", "launch_ros"} <= depends
    assert (PACKAGE / "resource" / "vsinv").is_file()  # the ament index marker setup.py installs
    setup = (PACKAGE / "setup.py").read_text()
    assert "vsinv_ros = vsinv.ros.__main__:main" in setup and "install_scripts=$base/lib/vsinv" in (PACKAGE / "setup.cfg").read_text()


def test_the_launch_file_declares_its_arguments() -> None:
    source = (PACKAGE / "launch" / "servo.launch.py").read_text()
    tree = ast.parse(source)
    assert any(isinstance(n, ast.FunctionDef) and n.name == "generate_launch_description" for n in tree.body)
    for argument in ("params_file", "image", "camera_info", "twist"):
        assert f'DeclareLaunchArgument("{argument}"' in source
    if importlib.util.find_spec("launch_ros") is None:
        pytest.skip("launch_ros is not importable: the launch description itself is not built here")


def test_the_parameters_file_is_read(tmp_path: Path) -> None:
    yaml = pytest.importorskip("yaml")
    parameters = yaml.safe_load((PACKAGE / "config" / "servo.yaml").read_text())["vsinv_ros"]["ros__parameters"]
    vsinv.save_image(np.zeros((48, 64), np.uint8), tmp_path / "reference.png")
    (tmp_path / "depths.csv").write_text("z\n" + "0.5\n" * 16)
    parameters.update(reference_image=str(tmp_path / "reference.png"), reference_depths_file=str(tmp_path / "depths.csv"))

    c = parse_parameters(flat(parameters))
    assert c.watchdog_timeout == 0.1 and c.image_reliability == "reliable" and c.image_depth == 1
    assert c.output_frame == "end_effector" and c.end_effector_frame == "tool0" and c.camera_frame == "camera_color_optical_frame"


def test_colcon_builds_the_package(tmp_path: Path) -> None:
    """colcon (when installed) builds ros/vsinv: the launch and parameters files in share/vsinv,
    the vsinv_ros executable in lib/vsinv (what ros2 run and launch_ros look for)."""
    import shutil
    import subprocess
    import sys

    colcon = shutil.which("colcon") or str(Path(sys.executable).parent / "colcon")
    if not Path(colcon).is_file():
        pytest.skip("colcon is not installed (pip install colcon-common-extensions)")
    done = subprocess.run([colcon, "build", "--base-paths", str(PACKAGE), "--build-base", str(tmp_path / "build"),
                           "--install-base", str(tmp_path / "install")], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    install = tmp_path / "install" / "vsinv"
    for path in ("share/vsinv/package.xml", "share/vsinv/launch/servo.launch.py", "share/vsinv/config/servo.yaml",
                 "share/ament_index/resource_index/packages/vsinv", "lib/vsinv/vsinv_ros"):
        assert (install / path).is_file(), path
