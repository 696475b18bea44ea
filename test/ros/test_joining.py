"""Servers that join a robot's fleet (ros/robot_parts.py): task candidates only once every
task stream's topic reaches them."""

from server_select.ros.robot_parts import Joining


class Stream(object):
    def __init__(self):
        self.reaches = set()

    def wired_to(self, server):
        return server in self.reaches


def test_a_joined_server_is_a_candidate_once_every_task_topic_reaches_it():
    sort, image, admitted = Stream(), Stream(), []
    joining = Joining([sort, image], admitted.append)
    joining.add(3)
    joining.add(4)
    assert admitted == []
    sort.reaches.update({3, 4})
    joining.check()
    assert admitted == []           # the image topic reaches neither yet
    image.reaches.add(4)
    joining.check()
    assert admitted == [4]
    image.reaches.add(3)
    joining.check()
    joining.check()
    assert admitted == [4, 3]       # each once


def test_a_server_that_leaves_before_its_topics_connect_is_never_a_candidate():
    stream, admitted = Stream(), []
    joining = Joining([stream], admitted.append)
    joining.add(5)
    joining.discard(5)
    stream.reaches.add(5)
    joining.check()
    assert admitted == []


def test_a_server_already_reached_is_a_candidate_at_once():
    stream, admitted = Stream(), []
    stream.reaches.add(2)
    Joining([stream], admitted.append).add(2)
    assert admitted == [2]
