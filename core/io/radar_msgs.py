"""A rosbags typestore that knows the official ROS 2 `radar_msgs` and `can_msgs` messages.

The definitions are those of ros-perception/radar_msgs (branch ros2): RadarReturn and
RadarScan for raw detections, RadarTrack and RadarTracks for tracked objects; and of
ros-industrial/ros_canopen (branch dashing-devel): can_msgs/Frame, one CAN frame. The ROS 2
Humble store already holds their dependencies (std_msgs/Header, geometry_msgs/Point and
Vector3, unique_identifier_msgs/UUID).

Notes:
    Bags that embed their message definitions (ROS 1 always, ROS 2 from rosbag2 version 8)
    are read with those; this store serves the older ROS 2 bags that embed none.
"""

from __future__ import annotations

from functools import cache

from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

RADAR_RETURN = "radar_msgs/msg/RadarReturn"
RADAR_SCAN = "radar_msgs/msg/RadarScan"
RADAR_TRACK = "radar_msgs/msg/RadarTrack"
RADAR_TRACKS = "radar_msgs/msg/RadarTracks"
COMPRESSED_IMAGE = "sensor_msgs/msg/CompressedImage"
IMAGE = "sensor_msgs/msg/Image"
CAN_FRAME = "can_msgs/msg/Frame"

RADAR_MSG_DEFINITIONS: dict[str, str] = {
    RADAR_RETURN: """
float32 range
float32 azimuth
float32 elevation
float32 doppler_velocity
float32 amplitude
""",
    RADAR_SCAN: """
std_msgs/Header header
radar_msgs/RadarReturn[] returns
""",
    RADAR_TRACK: """
uint16 NO_CLASSIFICATION=0
uint16 STATIC=1
uint16 DYNAMIC=2
unique_identifier_msgs/UUID uuid
geometry_msgs/Point position
geometry_msgs/Vector3 velocity
geometry_msgs/Vector3 acceleration
geometry_msgs/Vector3 size
uint16 classification
float32[6] position_covariance
float32[6] velocity_covariance
float32[6] acceleration_covariance
float32[6] size_covariance
""",
    RADAR_TRACKS: """
std_msgs/Header header
radar_msgs/RadarTrack[] tracks
""",
    CAN_FRAME: """
std_msgs/Header header
uint32 id
bool is_rtr
bool is_extended
bool is_error
uint8 dlc
uint8[8] data
""",
}


@cache
def typestore() -> Typestore:
    """The ROS 2 Humble typestore with the radar_msgs and can_msgs types registered (built once)."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    types = {}
    for name, text in RADAR_MSG_DEFINITIONS.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store
