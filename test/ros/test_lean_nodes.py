"""What a node loads: a robot or server of sort tasks needs neither numpy nor OpenCV."""


def test_a_node_that_sends_or_sorts_sort_tasks_loads_neither_numpy_nor_opencv():
    """The robot, server and manager modules import without numpy or cv2 (a robot with
    sort tasks only never needs them: 14 + 17 MiB of resident memory on a 1 GiB Pi)."""
    import subprocess
    import sys
    code = ('import sys\nimport server_select.nodes.robot, server_select.nodes.server, '
            'server_select.nodes.manager, server_select.tasks.sort\n'
            'from server_select.msg import LatencySample\n'
            'import io\nLatencySample(rtt=0.5).serialize(io.BytesIO())\n'
            'print(sorted(m for m in ("numpy", "cv2") if m in sys.modules))')
    import os
    src = os.path.join(os.path.dirname(__file__), '..', '..', 'src')   # after the devel space
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        p for p in (os.environ.get('PYTHONPATH'), src) if p))
    out = subprocess.run([sys.executable, '-c', code], stdout=subprocess.PIPE, env=env,
                         universal_newlines=True, check=True).stdout.strip()
    assert out == '[]'


def test_a_server_of_both_task_types_loads_opencv_once_a_robot_says_it_sends_frames():
    """A server loads OpenCV and its detectors when a robot's probe first names frames
    (``warm``), not at start (a fleet of sort tasks never needs them) and not with the
    first frame (on a slow server that frame, and the probes meanwhile, would wait)."""
    import os
    import subprocess
    import sys
    code = ('import sys\nimport server_select.nodes.server\n'
            'from server_select.core.settings import default\n'
            'from server_select.tasks.kinds import server_kinds\n'
            'kinds = dict((k.kind, k) for k in server_kinds(\n'
            '    lambda name, default_=None: default(name), 2))\n'
            'at_start = "cv2" in sys.modules\n'
            'kinds["sort"].warm()\n'
            'after_sort = "cv2" in sys.modules\n'
            'kinds["image"].warm()\n'
            'loaded = [d.classifier is not None for d in kinds["image"].detectors.queue]\n'
            'print(sorted(kinds), at_start, after_sort, "cv2" in sys.modules, loaded)')
    src = os.path.join(os.path.dirname(__file__), '..', '..', 'src')
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        p for p in (os.environ.get('PYTHONPATH'), src) if p))
    out = subprocess.run([sys.executable, '-c', code], stdout=subprocess.PIPE, env=env,
                         universal_newlines=True, check=True).stdout.strip()
    assert out == "['image', 'sort'] False False True [True, True]"
