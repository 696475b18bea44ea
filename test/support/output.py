"""What a command prints until a line holds a text: a launch or a viewer followed as a user
watches it, stopped once the line came (or at a time limit)."""

import os
import subprocess
import threading

from server_select.core.util.procs import stop_group


def output_until(argv, until, timeout):
    """Everything ``argv`` printed (stdout and stderr) until a line held ``until``, or
    ``timeout`` s passed, or it ended; its process group is then stopped. Unbuffered: a
    Python child's lines reach the pipe when written, not at its end."""
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            universal_newlines=True, start_new_session=True,
                            env=dict(os.environ, PYTHONUNBUFFERED='1'))
    lines = []
    timer = threading.Timer(timeout, stop_group, (proc,))
    timer.start()
    try:
        for line in proc.stdout:
            lines.append(line)
            if until in line:
                break
    finally:
        timer.cancel()
        stop_group(proc)
        lines += proc.stdout.readlines()
    return ''.join(lines)
