import os

import pytest

from server_select.vision.detection import Detector
from server_select.vision.image_source import FolderSource, SearchSource, SourceError, open_source
from server_select.vision.search import (Found, PathFollower, SearchError, SearchWorld,
                                         TargetRegistry, lawnmower, sample_image)


@pytest.fixture(scope='module')
def world():
    return SearchWorld(1600, 1200, [{'name': 'a', 'x': 400, 'y': 400, 'size': 220},
                                    {'name': 'b', 'x': 1200, 'y': 800, 'size': 200,
                                     'mirror': True}], seed=1)


def test_views_of_targets_show_faces_at_their_place(world):
    detector = Detector()
    for target in world.targets:
        boxes = detector.detect(world.view(target.x + 30, target.y - 20))
        assert len(boxes) == 1, target
        x, y = world.to_world(target.x + 30, target.y - 20, boxes[0][:4])
        assert world.target_at(x, y, 150) == target.name


def test_empty_ground_has_no_target(world):
    assert Detector().detect(world.view(800, 150)) == []
    assert world.target_at(800, 150, 150) is None


def test_view_outside_the_area_is_dark(world):
    frame = world.view(-1000, -1000)
    assert frame.shape == (480, 640, 3) and frame.max() == 0
    edge = world.view(0, 0)
    assert edge[:240, :320].max() == 0 and edge[240:, 320:].max() > 0


def test_target_must_fit():
    with pytest.raises(SearchError, match='does not fit'):
        SearchWorld(400, 400, [{'name': 'x', 'x': 10, 'y': 10, 'size': 200}])


def test_lawnmower_and_path_follower():
    points = lawnmower(0, 100, 0, 20, 10)
    assert points == [(0, 0), (100, 0), (100, 10), (0, 10), (0, 20), (100, 20)]
    path = PathFollower([(0, 0), (100, 0)], speed=10)
    assert path.position(0) == (0, 0)
    assert path.position(5) == pytest.approx((50, 0))
    assert path.position(15) == pytest.approx((50, 0))   # on the way back
    assert path.position(20) == pytest.approx((0, 0))


def test_registry_merges_by_distance():
    registry = TargetRegistry(radius=100)
    assert registry.add(Found(1, 5, 'face', 100, 100, 1.0))
    assert not registry.add(Found(2, 9, 'face', 150, 120, 2.0))
    assert registry.add(Found(2, 10, 'face', 400, 100, 3.0))
    assert [(f.robot_id, f.task_id) for f in registry.all()] == [(1, 5), (2, 10)]


def test_registry_keeps_at_most_its_limit():
    registry = TargetRegistry(radius=1, limit=2)
    assert registry.add(Found(1, 1, 'face', 0, 0, 1.0)) and not registry.full()
    assert registry.add(Found(2, 2, 'face', 10, 0, 2.0)) and registry.full()
    assert not registry.add(Found(3, 3, 'face', 20, 0, 3.0))
    assert [f.robot_id for f in registry.all()] == [1, 2]


def test_sources(tmp_path, world):
    import cv2
    cv2.imwrite(str(tmp_path / 'b.png'), sample_image('coffee.png'))
    cv2.imwrite(str(tmp_path / 'a.png'), sample_image('astronaut.png'))
    (tmp_path / 'notes.txt').write_text('not an image')
    folder = open_source(str(tmp_path))
    assert isinstance(folder, FolderSource)
    shapes = [folder.frame(0)[0].shape for _ in range(3)]
    assert shapes == [(512, 512, 3), (400, 600, 3), (512, 512, 3)]
    with pytest.raises(SourceError):
        open_source(str(tmp_path / 'missing'))
    empty = tmp_path / 'empty'
    empty.mkdir()
    with pytest.raises(SourceError, match='no images'):
        open_source(str(empty))
    strip = SearchSource(world, 1, 2, speed=100)
    frame, (x, y) = strip.frame(0)
    assert frame.shape == (480, 640, 3) and x >= 800


def test_shipped_search_area_loads():
    path = os.path.join(os.path.dirname(__file__), '..', '..', 'config', 'search_area.yaml')
    world = SearchWorld.load(path)
    assert len(world.targets) >= 3
