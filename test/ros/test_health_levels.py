"""The statuses' levels are diagnostic_msgs' own."""

from diagnostic_msgs.msg import DiagnosticStatus

from server_select.core.observe import health_status


def test_the_levels_are_diagnostic_msgs_levels():
    assert (health_status.OK, health_status.WARN, health_status.ERROR, health_status.STALE) \
        == (DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR,
            DiagnosticStatus.STALE)
