"""Modules a node loads only when it uses them (no rospy).

A robot that sends sort tasks needs neither numpy nor OpenCV, which would take 14 and
17 MiB of its resident memory (bench-robot; a Raspberry Pi 3 has 1 GiB for everything).

- :func:`deferred`: a module imported on first use of one of its attributes (the vision
  code's ``np = deferred('numpy')``: a camera robot loads numpy with its first frame).
- :func:`genpy_without_numpy`: genpy imports numpy when it can, only so that its check of a
  float field that failed to serialize also accepts numpy scalars
  (``genpy/message.py``, ``_valid_float_types``; the fields serialize the same without);
  run before rospy is first imported, it lets genpy load as if numpy were missing. Every
  node runs it (``server_select/nodes/__init__.py``).
"""

import importlib
import sys


class Deferred(object):
    """Module ``name``, imported when one of its attributes is first asked for."""

    def __init__(self, name):
        self.__dict__['_name'] = name

    def __getattr__(self, attr):
        return getattr(importlib.import_module(self.__dict__['_name']), attr)


def deferred(name):
    """The module ``name`` if it is loaded already, else a :class:`Deferred` one."""
    return sys.modules.get(name) or Deferred(name)


def genpy_without_numpy():
    """Load genpy without numpy (see the module's docstring); nothing once either is."""
    if 'genpy.message' in sys.modules or sys.modules.get('numpy') is not None:
        return
    sys.modules['numpy'] = None          # "import numpy" raises ImportError meanwhile
    try:
        import genpy.message  # noqa: F401
    finally:
        del sys.modules['numpy']
