"""The :class:`~server_select.core.load.work_queue.Load` a LatencyProbe answer reports,
once its shape and numbers are checked: a server's answer is read only as far as it makes
sense (a sealed answer can still come from a server with a bug)."""

import math

from server_select.core.load.work_queue import Load

MAX_KINDS = 32          # task kinds an answer may report (a fleet has a few)


def load_of(response):
    """The :class:`~server_select.core.load.work_queue.Load` of a LatencyProbe answer; a
    ValueError saying what is wrong with it when its kinds and their figures do not pair
    up, are too many, or a figure is not a finite number >= 0."""
    kinds = list(response.kinds)
    if not len(kinds) == len(response.service_time) == len(response.service_error):
        raise ValueError('%d kinds with %d work times and %d errors' % (
            len(kinds), len(response.service_time), len(response.service_error)))
    if len(kinds) > MAX_KINDS or len(set(kinds)) < len(kinds):
        raise ValueError('%d kinds (%d different; at most %d)' % (
            len(kinds), len(set(kinds)), MAX_KINDS))
    figures = dict(backlog=response.backlog, utilization=response.utilization)
    figures.update(('work of %s' % k, v) for k, v in zip(kinds, response.service_time))
    figures.update(('error of %s' % k, v) for k, v in zip(kinds, response.service_error))
    for name, value in sorted(figures.items()):
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError('%s is %r, not a finite number >= 0' % (name[:40], value))
    return Load(response.queued, response.in_service, max(1, response.workers),
                response.backlog, dict(zip(kinds, response.service_time)),
                response.utilization, dict(zip(kinds, response.service_error)))
