"""The ROS-free core's constants are the messages' own."""

from server_select.core.flow.outcome import LOCAL, NO_SERVER
from server_select.msg import SelectionFlag, TaskReport


def test_no_server_and_local_are_the_message_constants():
    assert NO_SERVER == TaskReport.NO_SERVER == SelectionFlag.NO_SERVER == -1
    assert LOCAL == TaskReport.LOCAL == -2
