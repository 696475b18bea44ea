"""``rosrun server_select launch FILE.launch [name:=value ...]``: roslaunch of one of the
package's launch files whose exit status a script or a systemd unit can trust.

roslaunch exits 0 when a node ends the launch for an invalid parameter (each node of the
package does, with one FATAL line), and says nothing of an argument no launch file
declares (``duraton:=10`` runs the demo with no duration, for ever). Here:

- an argument no launch file of the launch declares ends it before it starts: one line
  naming it and the nearest declared one, exit status 2;
- a node that ends the launch for an invalid parameter writes its name and reason to a
  file this command hands every node it starts (:data:`STATUS_ENV`): exit status 2, with
  that line again;
- otherwise roslaunch's own status (Ctrl-C, SIGTERM: passed on to it).
"""

import os
import signal
import subprocess
import sys
import tempfile

from server_select.core.util.bounded import peer

STATUS_ENV = 'SERVER_SELECT_LAUNCH_STATUS'    # the file a node's fatal line goes to
INVALID = 2


def record_fatal(node_name, why):
    """This node ends its launch for ``why``: one line in the launch's status file, when
    :func:`main` started the launch (nothing otherwise)."""
    path = os.environ.get(STATUS_ENV)
    if not path:
        return
    try:
        with open(path, 'a') as stream:
            stream.write('%s: %s\n' % (node_name, peer(str(why).replace('\n', ' '), 400)))
    except OSError:
        pass


def _undeclared(argv):
    """Lines for the arguments of ``roslaunch ARGV`` that no launch file declares."""
    from server_select.ros.launch_args import undeclared
    _, unknown = undeclared(['roslaunch'] + argv)
    return ['launch argument %s:= is declared by no launch file of this launch%s'
            % (name, '; did you mean %s:=?' % near if near else '') for name, near in unknown]


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    if not argv or argv[0] in ('-h', '--help'):
        print(__doc__.strip())
        return 0 if argv else INVALID
    if argv[0].endswith('.launch') and not os.path.isfile(argv[0]):
        argv = ['server_select'] + argv      # one of this package's (roslaunch's PACKAGE)
    try:
        refused = _undeclared(argv)
    except Exception as error:        # roslaunch says why, in its own words
        refused = ['cannot read the launch: %s' % error]
    if refused:
        for line in refused:
            print('launch: %s' % line, file=sys.stderr)
        return INVALID
    with tempfile.NamedTemporaryFile('r', prefix='launch_status_', suffix='.txt') as status:
        env = dict(os.environ, **{STATUS_ENV: status.name})
        proc = subprocess.Popen(['roslaunch'] + argv, env=env)
        for signum in (signal.SIGINT, signal.SIGTERM):
            signal.signal(signum, lambda number, _frame: proc.send_signal(number))
        code = proc.wait()
        fatal = status.read().splitlines()
    for line in fatal:
        print('launch: ended for an invalid parameter: %s' % line, file=sys.stderr)
    return INVALID if fatal else code


if __name__ == '__main__':
    sys.exit(main())
