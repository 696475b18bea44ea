"""A compressed camera frame goes to the server as the camera sent it (no decoding and
encoding again on the robot), with the camera's header; a raw camera's frames are
encoded as before."""

import numpy as np
import rospy
from sensor_msgs.msg import CompressedImage, Image

from server_select.ros.camera import TopicSource
from server_select.tasks.image import Frames
from server_select.vision import image_codec


class Sent(object):
    """A message as a subscriber with rospy.AnyMsg hands it over."""

    def __init__(self, msg):
        import io
        buff = io.BytesIO()
        msg.serialize(buff)
        self._buff = buff.getvalue()
        self._connection_header = {'type': msg._type}


def _camera_frame(seq):
    frame = np.full((48, 64, 3), seq * 10, dtype=np.uint8)
    fmt, data = image_codec.encode(frame, 80)
    msg = CompressedImage(format=fmt, data=data)
    msg.header.stamp, msg.header.frame_id = rospy.Time(100, seq), 'cam_optical'
    return msg


def test_a_compressed_frame_passes_through_once_with_its_header():
    source = TopicSource('/camera/image_raw/compressed')
    frames = Frames(1, {'transport': 'compressed'}, source=source)
    sent = _camera_frame(3)
    source.on_frame(Sent(sent))
    task, _ = frames.make(7, rospy.Time(5))
    assert task.compressed.data == sent.data and task.compressed.format == sent.format
    assert task.compressed.header.frame_id == 'cam_optical'
    assert task.compressed.header.stamp == rospy.Time(100, 3) and task.header.stamp.secs == 5
    assert source.used == 1 and not source.ready()         # each frame at most once


def test_a_raw_camera_or_a_raw_transport_is_encoded_as_before():
    source = TopicSource('/camera/image_raw')
    frames = Frames(1, {'transport': 'compressed'}, source=source)
    raw = Image(height=48, width=64, encoding='bgr8', step=64 * 3, data=bytes(48 * 64 * 3))
    raw.header.frame_id = 'cam'
    source.on_frame(Sent(raw))
    task, _ = frames.make(8, rospy.Time(5))
    assert task.compressed.data[:2] == b'\xff\xd8' and task.compressed.header.frame_id == 'cam'
    source.on_frame(Sent(_camera_frame(4)))
    task, _ = Frames(1, {'transport': 'raw'}, source=source).make(9, rospy.Time(5))
    assert task.image.width == 64 and not task.compressed.data
