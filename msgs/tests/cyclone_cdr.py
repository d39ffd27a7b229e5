#!/usr/bin/env python3
"""Reference CDR encodings from Cyclone DDS (the DDS that ROS 2 ships) for metrocell-msgs tests.

Declares the ROS 2 types as cyclonedds IdlStruct dataclasses with their DDS type names
(pkg::msg::dds_::Type_), reads a JSON list of {"type": "pkg/msg/Type", "value": {...}} from
stdin, and prints, one line per item, the hex of `value.serialize()` (encapsulation header
included). Serialising opens no DDS participant, so this needs no network namespace.
"""

import json
import sys
import typing
from dataclasses import dataclass

from cyclonedds.idl import IdlStruct
import cyclonedds.idl.types as t

TYPES = {}


def ros(pkg, name):
    def register(cls):
        TYPES[f"{pkg}/msg/{name}"] = cls
        return cls
    return register


@ros("builtin_interfaces", "Time")
@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: t.int32
    nanosec: t.uint32


@ros("builtin_interfaces", "Duration")
@dataclass
class Duration(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: t.int32
    nanosec: t.uint32


@ros("std_msgs", "Header")
@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@ros("std_msgs", "String")
@dataclass
class String(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str


@ros("sensor_msgs", "Temperature")
@dataclass
class Temperature(IdlStruct, typename="sensor_msgs::msg::dds_::Temperature_"):
    header: Header
    temperature: t.float64
    variance: t.float64


@ros("sensor_msgs", "RelativeHumidity")
@dataclass
class RelativeHumidity(IdlStruct, typename="sensor_msgs::msg::dds_::RelativeHumidity_"):
    header: Header
    relative_humidity: t.float64
    variance: t.float64


@ros("sensor_msgs", "FluidPressure")
@dataclass
class FluidPressure(IdlStruct, typename="sensor_msgs::msg::dds_::FluidPressure_"):
    header: Header
    fluid_pressure: t.float64
    variance: t.float64


@ros("sensor_msgs", "TimeReference")
@dataclass
class TimeReference(IdlStruct, typename="sensor_msgs::msg::dds_::TimeReference_"):
    header: Header
    time_ref: Time
    source: str


@ros("sensor_msgs", "Image")
@dataclass
class Image(IdlStruct, typename="sensor_msgs::msg::dds_::Image_"):
    header: Header
    height: t.uint32
    width: t.uint32
    encoding: str
    is_bigendian: t.uint8
    step: t.uint32
    data: t.sequence[t.uint8]


@ros("sensor_msgs", "RegionOfInterest")
@dataclass
class RegionOfInterest(IdlStruct, typename="sensor_msgs::msg::dds_::RegionOfInterest_"):
    x_offset: t.uint32
    y_offset: t.uint32
    height: t.uint32
    width: t.uint32
    do_rectify: bool


@ros("sensor_msgs", "CameraInfo")
@dataclass
class CameraInfo(IdlStruct, typename="sensor_msgs::msg::dds_::CameraInfo_"):
    header: Header
    height: t.uint32
    width: t.uint32
    distortion_model: str
    d: t.sequence[t.float64]
    k: t.array[t.float64, 9]
    r: t.array[t.float64, 9]
    p: t.array[t.float64, 12]
    binning_x: t.uint32
    binning_y: t.uint32
    roi: RegionOfInterest


@ros("sensor_msgs", "JointState")
@dataclass
class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    header: Header
    name: t.sequence[str]
    position: t.sequence[t.float64]
    velocity: t.sequence[t.float64]
    effort: t.sequence[t.float64]


@ros("geometry_msgs", "Point")
@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: t.float64
    y: t.float64
    z: t.float64


@ros("geometry_msgs", "PointStamped")
@dataclass
class PointStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PointStamped_"):
    header: Header
    point: Point


@ros("geometry_msgs", "Vector3")
@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: t.float64
    y: t.float64
    z: t.float64


@ros("geometry_msgs", "Wrench")
@dataclass
class Wrench(IdlStruct, typename="geometry_msgs::msg::dds_::Wrench_"):
    force: Vector3
    torque: Vector3


@ros("geometry_msgs", "WrenchStamped")
@dataclass
class WrenchStamped(IdlStruct, typename="geometry_msgs::msg::dds_::WrenchStamped_"):
    header: Header
    wrench: Wrench


@ros("geometry_msgs", "Quaternion")
@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: t.float64
    y: t.float64
    z: t.float64
    w: t.float64


@ros("geometry_msgs", "Pose")
@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point
    orientation: Quaternion


@ros("geometry_msgs", "PoseWithCovariance")
@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: Pose
    covariance: t.array[t.float64, 36]


@ros("geometry_msgs", "PoseWithCovarianceStamped")
@dataclass
class PoseWithCovarianceStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovarianceStamped_"):
    header: Header
    pose: PoseWithCovariance


@ros("geometry_msgs", "Transform")
@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3
    rotation: Quaternion


@ros("geometry_msgs", "TransformStamped")
@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    header: Header
    child_frame_id: str
    transform: Transform


@ros("tf2_msgs", "TFMessage")
@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    transforms: t.sequence[TransformStamped]


@ros("diagnostic_msgs", "KeyValue")
@dataclass
class KeyValue(IdlStruct, typename="diagnostic_msgs::msg::dds_::KeyValue_"):
    key: str
    value: str


@ros("diagnostic_msgs", "DiagnosticStatus")
@dataclass
class DiagnosticStatus(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticStatus_"):
    level: t.uint8  # `byte` in the .msg: one octet on the wire
    name: str
    message: str
    hardware_id: str
    values: t.sequence[KeyValue]


@ros("diagnostic_msgs", "DiagnosticArray")
@dataclass
class DiagnosticArray(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticArray_"):
    header: Header
    status: t.sequence[DiagnosticStatus]


@ros("rosgraph_msgs", "Clock")
@dataclass
class Clock(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
    clock: Time


@ros("metrocell_msgs", "TrackerMeasurement")
@dataclass
class TrackerMeasurement(IdlStruct, typename="metrocell_msgs::msg::dds_::TrackerMeasurement_"):
    header: Header
    target_id: t.bounded_str[64]
    point: Point
    range: t.float64
    azimuth: t.float64
    elevation: t.float64
    covariance: t.array[t.float64, 9]
    air_temperature: t.float64
    air_pressure: t.float64
    air_humidity: t.float64
    refractive_index: t.float64
    status: t.uint8


@ros("metrocell_msgs", "FiducialDetection")
@dataclass
class FiducialDetection(IdlStruct, typename="metrocell_msgs::msg::dds_::FiducialDetection_"):
    family: t.bounded_str[32]
    id: t.int32
    corners: t.sequence[t.float64]
    corner_covariance: t.sequence[t.float64]
    decision_margin: t.float64
    has_pose: bool
    pose: PoseWithCovariance


@ros("metrocell_msgs", "FiducialDetectionArray")
@dataclass
class FiducialDetectionArray(IdlStruct, typename="metrocell_msgs::msg::dds_::FiducialDetectionArray_"):
    header: Header
    image_width: t.uint32
    image_height: t.uint32
    detections: t.sequence[FiducialDetection]


@ros("metrocell_msgs", "ErrorModel")
@dataclass
class ErrorModel(IdlStruct, typename="metrocell_msgs::msg::dds_::ErrorModel_"):
    header: Header
    machine_id: str
    term_ids: t.sequence[str]
    parameter_names: t.sequence[str]
    units: t.sequence[str]
    values: t.sequence[t.float64]
    covariance: t.sequence[t.float64]
    residual_rms: t.float64
    observation_count: t.uint32
    degrees_of_freedom: t.uint32
    term_labels: t.sequence[str]
    term_catalog_ids: t.sequence[str]
    term_options: t.sequence[str]


@ros("metrocell_msgs", "MeasuredPoint")
@dataclass
class MeasuredPoint(IdlStruct, typename="metrocell_msgs::msg::dds_::MeasuredPoint_"):
    header: Header
    point_id: t.bounded_str[64]
    source: t.bounded_str[32]
    nominal: Point
    measured: Point
    covariance: t.array[t.float64, 9]


@ros("metrocell_msgs", "ProbeHit")
@dataclass
class ProbeHit(IdlStruct, typename="metrocell_msgs::msg::dds_::ProbeHit_"):
    header: Header
    probe_id: t.bounded_str[64]
    axis_names: t.sequence[str]
    axis_positions: t.sequence[t.float64]
    stylus_centre: Point
    approach_direction: Vector3
    stylus_radius: t.float64
    pretravel: t.float64
    surface_point: Point
    covariance: t.array[t.float64, 9]


def struct_inside(annotation):
    """The IdlStruct class an annotation is or contains (sequence[...] / array[...]), else None."""
    if isinstance(annotation, type) and issubclass(annotation, IdlStruct):
        return annotation
    for arg in typing.get_args(annotation):
        found = struct_inside(arg)
        if found is not None:
            return found
    return None


def build(cls, data):
    """Instantiates `cls` from a JSON mapping, recursing into nested structs."""
    kwargs = {}
    for name, annotation in cls.__annotations__.items():
        value = data[name]
        inner = struct_inside(annotation)
        if inner is not None:
            value = [build(inner, v) for v in value] if isinstance(value, list) else build(inner, value)
        kwargs[name] = value
    return cls(**kwargs)


def main():
    # Types not declared above (the complete std_msgs and rcl_interfaces packages) are built at
    # run time from the vendored .msg files by tests/py/ros2_peer.py; Cyclone still encodes them.
    import os
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tests", "py"))
    from ros2_peer import Types
    runtime = Types()
    items = json.load(sys.stdin)
    for item in items:
        cls = TYPES.get(item["type"])
        if cls is None:
            print(runtime.from_json(item["type"], item["value"]).serialize().hex())
            continue
        print(build(cls, item["value"]).serialize().hex())


if __name__ == "__main__":
    main()
