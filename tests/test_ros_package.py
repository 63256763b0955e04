"""The ROS 2 package in ros/vsinv (colcon, ament_python): package.xml, the launch file and its
parameters file, checked without ROS (the launch file itself runs only where launch_ros is)."""

from __future__ import annotations

import ast
import importlib.util
import sys
import types
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import vsinv
from ros_yaml import flat
from vsinv.ros import parse_parameters
from vsinv.ros.params import PARAMETERS

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
    # the description it builds: test_the_launch_description_starts_the_bridge_with_its_parameters_and_topics


def test_the_parameters_file_is_read(tmp_path: Path) -> None:
    yaml = pytest.importorskip("yaml")
    parameters = yaml.safe_load((PACKAGE / "config" / "servo.yaml").read_text())["vsinv_ros"]["ros__parameters"]
    vsinv.vision.save_image(np.zeros((48, 64), np.uint8), tmp_path / "reference.png")
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


class _Recorded:
    """A stand-in for a launch class: keeps what it is given."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.args, self.kwargs = args, kwargs


def _fake_module(name: str, **classes: type) -> types.ModuleType:
    module = types.ModuleType(name)
    for attr, cls in classes.items():
        setattr(module, attr, type(attr, (cls,), {}))
    return module


def _launch_description(monkeypatch: pytest.MonkeyPatch) -> list[Any]:
    """generate_launch_description() of the launch file run against recording fakes of launch,
    launch.actions, launch.substitutions, launch_ros.actions and ament_index_python.packages (the
    share directory: the package's source folder, whose layout setup.py installs as it is)."""
    fakes = {
        "launch": _fake_module("launch", LaunchDescription=_Recorded),
        "launch.actions": _fake_module("launch.actions", DeclareLaunchArgument=_Recorded),
        "launch.substitutions": _fake_module("launch.substitutions", LaunchConfiguration=_Recorded),
        "launch_ros": _fake_module("launch_ros"),
        "launch_ros.actions": _fake_module("launch_ros.actions", Node=_Recorded),
        "ament_index_python": _fake_module("ament_index_python"),
        "ament_index_python.packages": _fake_module("ament_index_python.packages"),
    }
    shares = {"vsinv": str(PACKAGE)}
    fakes["ament_index_python.packages"].get_package_share_directory = shares.__getitem__  # type: ignore[attr-defined]
    for name, module in fakes.items():
        monkeypatch.setitem(sys.modules, name, module)
    spec = importlib.util.spec_from_file_location("servo_launch", PACKAGE / "launch" / "servo.launch.py")
    assert spec is not None and spec.loader is not None
    launch_file = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(launch_file)
    description = launch_file.generate_launch_description()
    assert type(description).__name__ == "LaunchDescription" and len(description.args) == 1
    return list(description.args[0])


def _console_scripts() -> dict[str, str]:
    """setup.py's console_scripts, read from its syntax tree: {name: "module:function"}."""
    call = next(n for n in ast.walk(ast.parse((PACKAGE / "setup.py").read_text()))
                if isinstance(n, ast.Call) and getattr(n.func, "id", None) == "setup")
    entry_points = ast.literal_eval(next(k.value for k in call.keywords if k.arg == "entry_points"))
    return dict(tuple(s.strip() for s in line.split("=", 1)) for line in entry_points["console_scripts"])


def test_the_launch_description_starts_the_bridge_with_its_parameters_and_topics(monkeypatch: pytest.MonkeyPatch) -> None:
    actions = _launch_description(monkeypatch)
    kinds = [type(a).__name__ for a in actions]
    assert kinds.count("Node") == 1 and set(kinds) == {"Node", "DeclareLaunchArgument"}, kinds
    arguments = {a.args[0]: a.kwargs for a in actions if type(a).__name__ == "DeclareLaunchArgument"}
    assert set(arguments) == {"params_file", "image", "camera_info", "twist"}
    assert all(a.get("description") for a in arguments.values())
    defaults = {name: a["default_value"] for name, a in arguments.items()}

    def resolve(value: Any) -> str:  # a substitution (or a list of them) at the arguments' defaults
        if isinstance(value, list):
            return "".join(resolve(v) for v in value)
        if type(value).__name__ == "LaunchConfiguration":
            return str(defaults[value.args[0]])
        return str(value)

    node = next(a.kwargs for a in actions if type(a).__name__ == "Node")
    # the package's entry point: the console script setup.py declares, installed where ros2 run looks
    assert node["package"] == ET.parse(PACKAGE / "package.xml").getroot().findtext("name") == "vsinv"
    scripts = _console_scripts()
    assert node["executable"] in scripts, (node["executable"], scripts)
    module, function = scripts[node["executable"]].split(":")
    main = PACKAGE.parent.parent / "python" / Path(*module.split(".")).with_suffix(".py")
    assert any(isinstance(n, ast.FunctionDef) and n.name == function for n in ast.parse(main.read_text()).body), main
    assert "install_scripts=$base/lib/vsinv" in (PACKAGE / "setup.cfg").read_text()

    # the parameters file: in the package's config/, for this node, every key one the bridge declares
    [params_file] = [resolve(p) for p in node["parameters"]]
    assert Path(params_file) == PACKAGE / "config" / "servo.yaml" and Path(params_file).is_file()
    yaml = pytest.importorskip("yaml")
    document = yaml.safe_load(Path(params_file).read_text())
    assert set(document) == {node["name"]}, (set(document), node["name"])  # the node's parameters, not another's
    given = flat(document[node["name"]]["ros__parameters"])
    declared = {p.name for p in PARAMETERS}
    assert set(given) <= declared, sorted(set(given) - declared)

    # the remappings: from topics the node subscribes or publishes (at the file's settings) to the arguments
    topics = {k[: -len("_topic")]: given.get(k, p.default) for k, p in ((p.name, p) for p in PARAMETERS) if k.endswith("_topic")}
    node_topics = {*topics.values(), f"{topics['image'].rstrip('/')}/compressed"}  # image_transport's compressed topic
    remapped = {source: resolve(target) for source, target in node["remappings"]}
    assert set(remapped) <= node_topics, sorted(set(remapped) - node_topics)
    assert remapped == {topics["image"]: "/camera/image_raw", f"{topics['image']}/compressed": "/camera/image_raw/compressed",
                        topics["camera_info"]: "/camera/camera_info", topics["twist"]: "/servo_node/delta_twist_cmds"}
