"""Camera frames searched for targets, the second paper's task, as a task type (built in:
``~image_source`` or ``~image_topic`` on a robot).

Robot side: frames from a source (a folder, a video, a synthetic search area, or a camera
topic), sent raw or compressed; where each was taken goes to the cooperative search. Server
side: the frame is searched with an OpenCV detector (one per worker), the annotated frame
goes back in the result and what was found on ``detections``, under the frame's own header
(its camera stamp and frame_id).
"""

import queue
import time

from sensor_msgs.msg import CompressedImage, Image, RegionOfInterest
from std_msgs.msg import Header

from server_select.core.config import names
from server_select.msg import Detection, Detections, ImageResult, ImageTask
from server_select.ros.node import fleet
from server_select.ros.plugins import MESSAGE_SLACK, TaskPlugin
from server_select.ros.seal import SealedPublisher
from server_select.vision import image_codec
from server_select.vision.detection import search_frame


class Frames(TaskPlugin):
    """One camera frame a task. Settings: ``encoding`` (bgr8), ``transport`` (raw or
    compressed), ``quality`` (JPEG, 80), ``max_pixels`` (larger frames are refused), and
    on a robot ``start`` (the source's time zero, epoch seconds; 0: now)."""

    kind = 'image'
    newest_wins = True        # a frame nobody waits for any more is worth nothing
    task_topic, task_type = names.IMAGE_TASK_TOPIC, ImageTask
    result_topic, result_type = names.IMAGE_RESULT_TOPIC, ImageResult

    def __init__(self, robot_id, settings, source=None, search=None, detectors=()):
        """``source``: a robot's frames (``frame(t)`` -> ``(array, where)``; a camera topic's
        also has ``last_header``, the camera's stamp and frame_id of that frame); ``search``:
        its SearchParticipant (or None); ``detectors``: the server's, one per worker (a robot
        in mode local has one too)."""
        super(Frames, self).__init__(robot_id, settings)
        self.input = settings.get('input', 'the frame source')
        self.encoding = settings.get('encoding', 'bgr8')
        self.transport = settings.get('transport', 'raw')
        self.quality = int(settings.get('quality', 80))
        self.max_pixels = int(settings.get('max_pixels', image_codec.MAX_PIXELS))
        self.source, self.search = source, search
        self.detectors = queue.Queue()
        for detector in detectors:
            self.detectors.put(detector)
        start = settings.get('start', 0.0)
        # the source's time zero: now, or the epoch time ``start`` (a shared clock)
        self.t0 = time.monotonic() - (time.time() - start if start else 0.0)
        self.detections_pub = None

    # -- robot side ---------------------------------------------------------------------------

    def ready(self):
        """Whether a frame is there to send (a camera topic may not have sent one yet)."""
        return getattr(self.source, 'ready', lambda: True)()

    def capture(self, task_id):
        """A frame from the source in ``encoding``; the search learns where it was."""
        frame, where = self.source.frame(time.monotonic() - self.t0)
        if self.search is not None:
            self.search.remember(task_id, where)
        return image_codec.convert(frame, self.encoding)

    def make(self, task_id, stamp):
        if self.transport == 'compressed' and self.encoding == 'bgr8':
            passed = self._pass_through(task_id, stamp)
            if passed is not None:
                return passed, None
        frame = self.capture(task_id)
        # the frame's own header: a camera's stamp and frame_id, which the server's result
        # and detections keep; a synthetic source's frame is taken now, by the robot
        camera = getattr(self.source, 'last_header', None)
        header = Header(stamp=camera.stamp, frame_id=camera.frame_id) if camera is not None \
            else Header(stamp=stamp, frame_id='robot%d_camera' % self.robot_id)
        task = ImageTask(header=Header(stamp=stamp), robot_id=self.robot_id, task_id=task_id)
        if self.transport == 'compressed':
            fmt, data = image_codec.encode(frame, self.quality)
            task.compressed = CompressedImage(header=header, format=fmt, data=data)
        else:
            encoding, height, width, step, data = image_codec.from_array(frame, self.encoding)
            task.image = Image(header=header, height=height, width=width, encoding=encoding,
                               step=step, data=data)
        return task, None

    def _pass_through(self, task_id, stamp):
        """A task of a compressed camera frame as it came (None: the source has none): a
        Pi 3 robot would spend most of a core decoding and encoding 5 frames a second
        (bench-robot); the server decodes it, and checks its size, as any frame."""
        image = getattr(self.source, 'compressed', lambda: None)()
        if image is None:
            return None
        if self.search is not None:
            self.search.remember(task_id, None)     # a camera's frames carry no position
        task = ImageTask(header=Header(stamp=stamp), robot_id=self.robot_id, task_id=task_id)
        task.compressed = CompressedImage(header=image.header, format=image.format,
                                          data=image.data)
        return task

    def check(self, result, _context):
        if result.image.width == 0 and not result.compressed.data:
            return 'result carries no annotated image'
        return None

    def run_local(self, task_id, _stamp):
        # The same work a server does for a frame (message fields in, detection,
        # annotation), so that robot CPU with and without offloading compare fairly.
        boxes, _ = self._search(image_codec.from_array(self.capture(task_id), self.encoding),
                                ('', b''))
        if self.search is not None:
            self.search.found_in(task_id, [(b.x, b.y, b.width, b.height, b.label)
                                           for b in boxes])
        return None

    # -- server side --------------------------------------------------------------------------

    def warm(self):
        """Load OpenCV and every worker's detector (on a server capped at a tenth of a
        core: seconds, during which its probe answers are late too)."""
        with self.detectors.mutex:       # (those a worker holds load with its frame)
            detectors = list(self.detectors.queue)
        for detector in detectors:
            detector.load()

    def start(self):
        self.detections_pub = SealedPublisher(fleet(names.DETECTIONS_TOPIC), Detections,
                                              queue_size=100)

    def max_bytes(self):
        """A raw 3-channel frame of ``max_pixels`` (a compressed one is shorter)."""
        return 3 * self.max_pixels + MESSAGE_SLACK

    def handle(self, task, result):
        boxes = self.rehearse(task, result)
        header = task.image.header if not task.compressed.data else task.compressed.header
        self.detections_pub.publish(Detections(
            header=header, robot_id=task.robot_id, task_id=task.task_id,
            server_id=result.server_id, detections=[
                Detection(roi=RegionOfInterest(x_offset=b.x, y_offset=b.y, width=b.width,
                                               height=b.height),
                          label=b.label, score=b.score) for b in boxes]))

    def rehearse(self, task, result):
        """The frame searched and ``result`` made, nothing shared (the boxes found)."""
        img, packed = task.image, task.compressed
        raw = not packed.data
        boxes, annotated = self._search((img.encoding, img.height, img.width, img.step,
                                         img.data), (packed.format, packed.data))
        if raw:
            encoding, height, width, step, data = image_codec.from_array(annotated)
            result.image = Image(header=img.header, height=height, width=width,
                                 encoding=encoding, step=step, data=data)
        else:
            fmt, data = image_codec.encode(annotated, self.quality)
            result.compressed = CompressedImage(header=packed.header, format=fmt, data=data)
        result.detection_count = len(boxes)
        return boxes

    def _search(self, raw, packed):
        """Boxes and annotated frame of a raw or ``packed`` frame, with a detector of this
        worker's own (ImageError, a ValueError, when it cannot be decoded or is too big)."""
        detector = self.detectors.get()
        try:
            return search_frame(detector, raw, packed, self.max_pixels)
        finally:
            self.detectors.put(detector)
