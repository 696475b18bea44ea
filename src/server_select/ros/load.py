"""A load-aware robot's view of its servers' load, fed by its probe answers
(:class:`~server_select.core.load.LoadBoard`)."""

from server_select.core.load import Load, LoadBoard


def load_of(response):
    """The :class:`~server_select.core.load.Load` a LatencyProbe answer reports."""
    return Load(response.queued, response.in_service, max(1, response.workers),
                response.backlog, dict(zip(response.kinds, response.service_time)))


class RobotLoad(object):
    """What the robot's tasks would wait for at each server: ``mix`` is ``{kind: tasks
    per second}`` of the robot's streams."""

    def __init__(self, mix):
        self.board = LoadBoard(mix)

    def on_answer(self, server, response):
        """A probe answer of ``server`` (the Prober's ``load_of``): its wait (s)."""
        self.board.update(server, load_of(response))
        return self.board.wait(server)

    def sent(self, server, kind):
        self.board.sent(server, kind)

    def expected(self, kind):
        """``(server) -> seconds``: backlog + work of a ``kind`` task there (None: unknown),
        what an attempt's deadline follows."""
        return lambda server: self.board.expected(server, kind)

    def forget(self, server):
        self.board.forget(server)
