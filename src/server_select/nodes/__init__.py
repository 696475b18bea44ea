"""The nodes. A node loads numpy only when it uses it (core/util/lazy.py)."""

from server_select.core.util.lazy import genpy_without_numpy

genpy_without_numpy()
