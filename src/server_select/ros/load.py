"""The :class:`~server_select.core.load.work_queue.Load` a LatencyProbe answer reports."""

from server_select.core.load.work_queue import Load


def load_of(response):
    """The :class:`~server_select.core.load.work_queue.Load` of a LatencyProbe answer."""
    return Load(response.queued, response.in_service, max(1, response.workers),
                response.backlog, dict(zip(response.kinds, response.service_time)),
                response.utilization, dict(zip(response.kinds, response.service_error)))
