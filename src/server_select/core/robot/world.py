"""What a :class:`~server_select.core.robot.robot.Robot` asks of the world around it
(:class:`Transport`) and what it tells (:class:`Events`): the robot node implements both
with rospy, the simulator with its modelled network and records, the parity test with a
script and a list. Both are no-ops here, so a driver overrides only what it has."""


class Transport(object):
    """How the robot reaches its servers. Every call returns at once; what comes back later
    reaches the robot as ``probe_answered`` / ``probe_failed`` and a stream's ``resolve``."""

    def connect(self, server):
        """``server`` is one of the robot's now: get ready to probe it and send it tasks."""

    def disconnect(self, server):
        """``server`` left: close what leads to it."""

    def probe(self, server, seq, kinds, rates):
        """Send probe ``seq`` to ``server``, announcing ``rates`` tasks a second of each of
        ``kinds``. Returns a handle whose ``out_for()``, if it has one, gives the seconds the
        request has been out by the clock round trips are measured with (None: unknown)."""
        return None

    def send_task(self, kind, request, server, budget):
        """Send a ``kind`` task's ``request`` to ``server``; ``budget``: the seconds the
        robot still waits for it (None: not load-aware, the server is told nothing)."""

    def heard(self, server, rtt):
        """``server`` answered a probe in ``rtt`` s: a task connection to it that stalled
        in TCP's back-off during an outage is made anew."""

    def wired(self, server):
        """Whether every task stream's connection reaches ``server`` (a task sent before
        that reaches nobody)."""
        return True

    def unready(self, kind):
        """What ``kind``'s tasks still wait for before the first is sent ('' : nothing),
        besides the robot's own readiness."""
        return ''


class Events(object):
    """What the robot tells its observers, in the order it happens."""

    def round(self, number, servers):
        """Probe round ``number`` probes ``servers`` (a still-out one: a failed sample)."""

    def sample(self, server, seq, rtt, error, wait, round_number):
        """A probe sample: ``rtt`` s (None: failed, for ``error``), the ``wait`` an answer
        reported (None: none), of round ``round_number``."""

    def bad_sample(self, server, error):
        """A sample of ``server`` the selection refused (``error``: a ValueError)."""

    def task_sample(self, server, seconds):
        """An answered task became a latency sample of ``server`` (``~passive``)."""

    def ejected(self, server, ejection, why):
        """``server`` failed (``why``) and the health table ejected it (``ejection``: its
        seconds; 0: it has not answered yet)."""

    def moved(self, server, why, kind):
        """The per-task rule moved the robot's ``kind`` tasks to ``server`` for ``why``."""

    def waiting(self, kind, what):
        """``kind``'s first task waits for ``what``."""

    def no_input(self, kind, seconds):
        """``kind`` has had no input for its tasks for ``seconds``."""

    def started(self, kind):
        """``kind``'s first task is sent."""

    def report(self, outcome):
        """A task ended (an :class:`~server_select.core.flow.outcome.Outcome`), once."""
