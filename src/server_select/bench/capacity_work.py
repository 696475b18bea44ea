"""The capacity benchmark's work (:mod:`server_select.bench.capacity`): the camera frame
robots send, and the CPU seconds one task of a kind takes a server on one core of this
machine (what the servers' capacity is computed from)."""

import io
import random
import time

from server_select.core.flow.sort_kernel import make_values, sort_values
from server_select.msg import SortResult, SortTask
from server_select.vision import image_codec
from server_select.vision.detection import Detector, search_frame
from server_select.vision.image_source import frame

SORT_SIZE = 20000    # 80 kB a task: on this testbed bytes, not CPU, limit larger ones


def cpu_per_task(kind, repeats=10):
    """CPU seconds one task takes a server on one core (measured here)."""
    if kind == 'image':
        fmt, data = image_codec.encode(frame(), 80)
        detector = Detector()
        work = lambda: search_frame(detector, ('', 0, 0, 0, b''), (fmt, data))  # noqa: E731
    else:       # what a server does with a sort task: the message in, sorted, out
        values = make_values(random.Random(1), SORT_SIZE)
        buff = io.BytesIO()
        SortTask(data=values).serialize(buff)
        work = lambda: sort_message(buff.getvalue())     # noqa: E731
    work()
    start = time.process_time()
    for _ in range(repeats):
        work()
    return (time.process_time() - start) / repeats


def sort_message(raw):
    task = SortTask()
    task.deserialize(raw)
    SortResult(data=sort_values(task.data, len(task.data))).serialize(io.BytesIO())
