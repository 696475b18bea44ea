"""What a queued task is counted to hold (``ros/plugins.held_bytes``, what the server's
``~max_queue_bytes`` bounds): numbers, strings and byte arrays, nested messages."""

from server_select.msg import Detection, Detections, ImageTask, SortTask
from server_select.ros.plugins import PER_NUMBER, held_bytes


def test_an_array_of_numbers_counts_each_number():
    assert held_bytes(SortTask(data=tuple(range(100000)))) == 100000 * PER_NUMBER
    assert held_bytes(SortTask(data=[])) == 0


def test_strings_and_bytes_count_their_lengths_in_nested_messages_too():
    task = ImageTask()
    task.image.data, task.image.encoding = b'x' * 1000, 'mono8'
    task.compressed.data, task.compressed.format = b'y' * 500, 'jpeg'
    assert held_bytes(task) == 1000 + len('mono8') + 500 + len('jpeg')


def test_an_array_of_messages_counts_what_each_holds():
    found = Detections(detections=[Detection(label='face'), Detection(label='person')])
    assert held_bytes(found) == len('face') + len('person')
