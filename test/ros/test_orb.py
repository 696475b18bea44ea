"""The ORB plug-in, both sides, without a master."""

import cv2
import pytest

from server_select.msg import OrbResult
from server_select.tasks.orb import Orb
from server_select.vision.features import orb_features
from server_select.vision.search import sample_image


def test_orb_features_of_a_photo_and_of_a_blank_frame():
    points, descriptors = orb_features(sample_image('astronaut.png'), 200)
    assert 100 <= len(points) <= 200 and descriptors.shape == (len(points), 32)
    points, descriptors = orb_features(sample_image('astronaut.png')[:40, :40] * 0, 200)
    assert points.shape == (0, 2) and descriptors.shape == (0, 32)


def test_a_robot_makes_what_a_server_answers_and_checks_it(tmp_path):
    cv2.imwrite(str(tmp_path / 'a.png'), sample_image('astronaut.png'))
    robot = Orb(7, {'source': str(tmp_path), 'max_features': 150})
    server = Orb(None, {})
    task, context = robot.make(3, None)
    assert (task.robot_id, task.task_id, task.max_features) == (7, 3, 150)
    result = OrbResult(robot_id=7, task_id=3)
    server.handle(task, result)
    assert 100 <= result.count <= 150 and robot.check(result, context) is None
    result.descriptors = result.descriptors[:-1]
    assert 'inconsistent result' in robot.check(result, context)
    assert robot.run_local(4, None) is None


def test_settings_are_checked():
    with pytest.raises(ValueError) as info:
        Orb(1, {})
    assert 'source: required' in str(info.value)
