"""ROS 2 message definitions (``ros2msg`` text) and builders for a recorded run.

MCAP stores each schema as its ``.msg`` text followed by the definitions it
depends on (``MSG: pkg/Type`` sections), which is what ROS 2 bags, Foxglove
and `mcap_ros2` read. The field lists are those of the ROS 2 interfaces
(std_msgs, geometry_msgs, nav_msgs, sensor_msgs), without their comments.

Topics of a run (all in SI units, REP 103 frames ``odom`` and ``base_link``):

- ``/robotlib/state`` (std_msgs/Float64MultiArray): the lossless record of
  one poll, one float64 per `STATE_FIELDS` entry (replay reads this);
- ``/odom`` (nav_msgs/Odometry): odometry pose and velocity;
- ``/sonar`` (sensor_msgs/PointCloud2): one point per transducer, where its
  echo lies in ``base_link``, with its ``range`` (float64 fields);
- ``/scan`` (sensor_msgs/LaserScan): a laser's ranges, where present;
- ``/ground_truth`` (geometry_msgs/PoseStamped): the true pose, where the
  backend has one;
- ``/robotlib/command`` (std_msgs/String): each motion command as sent
  (``"MOVE 0.5"``), and ``/cmd_vel`` (geometry_msgs/Twist) for velocity ones.

Imports nothing of robotlib.
"""

from __future__ import annotations

import math

import numpy as np

_SEP = "\n" + "=" * 80 + "\n"

_DEFS = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec\n",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
    "std_msgs/String": "string data\n",
    "std_msgs/MultiArrayDimension": "string label\nuint32 size\nuint32 stride\n",
    "std_msgs/MultiArrayLayout": (
        "std_msgs/MultiArrayDimension[] dim\nuint32 data_offset\n"
    ),
    "std_msgs/Float64MultiArray": "std_msgs/MultiArrayLayout layout\nfloat64[] data\n",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Pose": (
        "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n"
    ),
    "geometry_msgs/PoseStamped": "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
    "geometry_msgs/PoseWithCovariance": (
        "geometry_msgs/Pose pose\nfloat64[36] covariance\n"
    ),
    "geometry_msgs/Twist": (
        "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n"
    ),
    "geometry_msgs/TwistWithCovariance": (
        "geometry_msgs/Twist twist\nfloat64[36] covariance\n"
    ),
    "nav_msgs/Odometry": (
        "std_msgs/Header header\nstring child_frame_id\n"
        "geometry_msgs/PoseWithCovariance pose\n"
        "geometry_msgs/TwistWithCovariance twist\n"
    ),
    "sensor_msgs/PointField": (
        "uint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\n"
        "uint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\n"
        "string name\nuint32 offset\nuint8 datatype\nuint32 count\n"
    ),
    "sensor_msgs/PointCloud2": (
        "std_msgs/Header header\nuint32 height\nuint32 width\n"
        "sensor_msgs/PointField[] fields\nbool is_bigendian\nuint32 point_step\n"
        "uint32 row_step\nuint8[] data\nbool is_dense\n"
    ),
    "sensor_msgs/LaserScan": (
        "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\n"
        "float32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\n"
        "float32 range_min\nfloat32 range_max\nfloat32[] ranges\n"
        "float32[] intensities\n"
    ),
}


def _deps(name: str, seen: list[str]) -> None:
    for line in _DEFS[name].splitlines():
        kind = line.split()[0].split("[")[0]
        if "/" in kind and kind not in seen:
            seen.append(kind)
            _deps(kind, seen)


def msgdef(name: str) -> str:
    """Return the full ``ros2msg`` schema text of ``name`` (with its dependencies)."""
    deps: list[str] = []
    _deps(name, deps)
    text = _DEFS[name]
    for d in deps:
        text += _SEP + f"MSG: {d}\n" + _DEFS[d]
    return text


STATE_FIELDS = (
    "time", "x", "y", "theta", "v", "w", "stalled", "motors_enabled",
    "true_x", "true_y", "true_theta",
)  # fmt: skip
"""Leading columns of ``/robotlib/state``; the sonar ranges (m) follow."""

TOPICS = {
    "/robotlib/state": "std_msgs/Float64MultiArray",
    "/odom": "nav_msgs/Odometry",
    "/sonar": "sensor_msgs/PointCloud2",
    "/scan": "sensor_msgs/LaserScan",
    "/ground_truth": "geometry_msgs/PoseStamped",
    "/robotlib/command": "std_msgs/String",
    "/cmd_vel": "geometry_msgs/Twist",
}
"""Topic to ROS 2 message type."""


def stamp(t: float) -> dict:
    """Return a ``builtin_interfaces/Time`` for ``t`` s."""
    ns = int(round(t * 1e9))
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def header(t: float, frame: str) -> dict:
    """Return a ``std_msgs/Header``."""
    return {"stamp": stamp(t), "frame_id": frame}


def pose_msg(pose) -> dict:
    """Return a ``geometry_msgs/Pose`` for ``(x, y, theta)``."""
    x, y, th = (float(v) for v in pose)
    return {
        "position": {"x": x, "y": y, "z": 0.0},
        "orientation": {
            "x": 0.0,
            "y": 0.0,
            "z": math.sin(th / 2),
            "w": math.cos(th / 2),
        },
    }


def twist_msg(v: float, w: float) -> dict:
    """Return a ``geometry_msgs/Twist`` (forward speed ``v``, turn rate ``w``)."""
    return {
        "linear": {"x": float(v), "y": 0.0, "z": 0.0},
        "angular": {"x": 0.0, "y": 0.0, "z": float(w)},
    }


def state_msg(row: np.ndarray) -> dict:
    """``/robotlib/state``: the row, its columns named in the layout's label."""
    n_sonar = len(row) - len(STATE_FIELDS)
    label = ",".join((*STATE_FIELDS, *(f"sonar{i}" for i in range(n_sonar))))
    return {
        "layout": {
            "dim": [{"label": label, "size": len(row), "stride": len(row)}],
            "data_offset": 0,
        },
        "data": [float(v) for v in row],
    }


def odometry_msg(t: float, pose, velocity) -> dict:
    """``/odom``: a ``nav_msgs/Odometry``."""
    return {
        "header": header(t, "odom"),
        "child_frame_id": "base_link",
        "pose": {"pose": pose_msg(pose), "covariance": [0.0] * 36},
        "twist": {"twist": twist_msg(*velocity), "covariance": [0.0] * 36},
    }


_CLOUD_FIELDS = [
    {"name": n, "offset": 8 * i, "datatype": 8, "count": 1}
    for i, n in enumerate(("x", "y", "z", "range"))
]


def sonar_cloud_msg(t: float, ranges, sonar_poses) -> dict:
    """``/sonar``: each transducer's echo point in ``base_link`` and its range.

    Parameters
    ----------
    t : float
        Time, s.
    ranges : array_like, shape (S,)
        Ranges, m.
    sonar_poses : array_like, shape (S, 3)
        Transducer poses in the robot frame, m and rad.
    """
    r = np.asarray(ranges, dtype=float)
    sp = np.asarray(sonar_poses, dtype=float)
    pts = np.column_stack(
        [
            sp[:, 0] + r * np.cos(sp[:, 2]),
            sp[:, 1] + r * np.sin(sp[:, 2]),
            np.zeros(len(r)),
            r,
        ]
    )
    data = np.ascontiguousarray(pts, dtype="<f8").tobytes()
    return {
        "header": header(t, "base_link"),
        "height": 1,
        "width": len(r),
        "fields": _CLOUD_FIELDS,
        "is_bigendian": False,
        "point_step": 32,
        "row_step": 32 * len(r),
        "data": data,
        "is_dense": True,
    }


def laser_msg(t: float, ranges, angle_min: float, angle_max: float, max_range: float):
    """``/scan``: a ``sensor_msgs/LaserScan`` (ranges in m, evenly spaced)."""
    r = np.asarray(ranges, dtype=float)
    inc = (angle_max - angle_min) / max(len(r) - 1, 1)
    return {
        "header": header(t, "laser"),
        "angle_min": float(angle_min),
        "angle_max": float(angle_max),
        "angle_increment": float(inc),
        "time_increment": 0.0,
        "scan_time": 0.0,
        "range_min": 0.0,
        "range_max": float(max_range),
        "ranges": [float(v) for v in r],
        "intensities": [],
    }
