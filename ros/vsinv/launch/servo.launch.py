"""``ros2 launch vsinv servo.launch.py [params_file:=FILE] [image:=TOPIC] [camera_info:=TOPIC]
[twist:=TOPIC]``: the vsinv_ros bridge with a parameters file (default: the package's
config/servo.yaml) and its image, CameraInfo and twist topics remapped."""

from pathlib import Path

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description() -> LaunchDescription:
    default_params = str(Path(get_package_share_directory("vsinv")) / "config" / "servo.yaml")
    arguments = [
        DeclareLaunchArgument("params_file", default_value=default_params, description="the bridge's parameters (YAML)"),
        DeclareLaunchArgument("image", default_value="/camera/image_raw", description="sensor_msgs/Image in"),
        DeclareLaunchArgument("camera_info", default_value="/camera/camera_info", description="sensor_msgs/CameraInfo in"),
        DeclareLaunchArgument("twist", default_value="/servo_node/delta_twist_cmds", description="TwistStamped out (MoveIt Servo)"),
    ]
    bridge = Node(
        package="vsinv",
        executable="vsinv_ros",
        name="vsinv_ros",
        output="screen",
        parameters=[LaunchConfiguration("params_file")],
        remappings=[
            ("image", LaunchConfiguration("image")),
            ("image/compressed", [LaunchConfiguration("image"), "/compressed"]),  # image_transport: compressed
            ("camera_info", LaunchConfiguration("camera_info")),
            ("~/twist", LaunchConfiguration("twist")),
        ],
    )
    return LaunchDescription([*arguments, bridge])
