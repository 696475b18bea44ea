"""Frames from a camera topic: any sensor_msgs/Image or sensor_msgs/CompressedImage topic."""

import threading

import genpy
import rospy
from sensor_msgs.msg import CompressedImage, Image

from server_select.vision import image_codec   # numpy, cv2: with the first frame decoded
from server_select.vision.image_source import SourceError


class TopicSource(object):
    """The newest frame of ``topic`` (usb_cam, a bag, a simulator's camera), each frame at
    most once: a robot offloads at the slower of its ``~frame_rate`` and the camera's.

    The topic's type is told by its publisher's connection header, so one parameter serves
    raw and compressed cameras (the ``.../compressed`` topic of image_transport).
    """

    world = None   # frames carry no position in a search area

    def __init__(self, topic, max_pixels=image_codec.MAX_PIXELS):
        self.topic, self.max_pixels = topic, max_pixels
        self._lock = threading.Lock()
        self._newest = None
        self.received = self.used = 0
        self.last_header = None     # the camera's header of the frame given last
        self.sub = None

    def start(self):
        self.sub = rospy.Subscriber(self.topic, rospy.AnyMsg, self.on_frame, queue_size=1,
                                    buff_size=1 << 24, tcp_nodelay=True)

    def on_frame(self, msg):
        with self._lock:
            self._newest = msg
            self.received += 1

    def ready(self):
        with self._lock:
            return self._newest is not None

    def compressed(self):
        """The newest frame not used yet as the camera sent it (a CompressedImage in JPEG
        or PNG, then used), for a task that travels compressed: no decoding and encoding
        again on the robot. None when there is no such frame (a raw camera: :meth:`frame`)."""
        with self._lock:
            msg = self._newest
            kind = (getattr(msg, '_connection_header', None) or {}).get('type')
            if kind != 'sensor_msgs/CompressedImage':
                return None
            self._newest = None
        self.used += 1
        try:
            image = CompressedImage().deserialize(msg._buff)
        except genpy.DeserializationError as error:
            raise SourceError('%s: a frame that does not deserialize: %s' % (self.topic, error))
        if not any(k in image.format.lower() for k in ('jpeg', 'jpg', 'png')):
            raise SourceError('%s: frames in %r, not JPEG or PNG' % (self.topic, image.format))
        self.last_header = image.header
        return image

    def frame(self, _t):
        """The newest frame not used yet, as an array (SourceError when there is none, or
        it is of another type; ImageError when it does not decode); its camera header
        (stamp, frame_id) is then :attr:`last_header`."""
        with self._lock:
            msg, self._newest = self._newest, None
        if msg is None:
            raise SourceError('no new frame on %s' % self.topic)
        self.used += 1
        kind = (getattr(msg, '_connection_header', None) or {}).get('type')
        if kind not in ('sensor_msgs/CompressedImage', 'sensor_msgs/Image'):
            raise SourceError('%s carries %s, not sensor_msgs/Image or CompressedImage'
                              % (self.topic, kind))
        try:
            image = (CompressedImage if kind.endswith('CompressedImage') else Image)() \
                .deserialize(msg._buff)
        except genpy.DeserializationError as error:
            raise SourceError('%s: a frame that does not deserialize: %s' % (self.topic, error))
        self.last_header = image.header
        if kind.endswith('CompressedImage'):
            return image_codec.decode(image.format, image.data, self.max_pixels), None
        return image_codec.task_frame(
            (image.encoding, image.height, image.width, image.step, image.data),
            ('', b''), self.max_pixels), None
