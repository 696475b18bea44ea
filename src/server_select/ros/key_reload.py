"""Key rotation without a restart: every node with a key serves ``~reload_keys``
(``server_select/ReloadKeys``), which reads its key files again
(:func:`server_select.ros.seal.reload_keys`), and ``rosrun server_select reload_keys`` calls
every node's on the master and prints what each now signs with and admits.

An operator's rotation, every node serving throughout:

1. the new key into every host's ``~fleet_key_next`` file, then ``reload_keys``: every
   node admits both keys;
2. the two files swapped on every host, then ``reload_keys``: every node signs with the
   new key and still admits the old one, from nodes not yet told.

The old key is admitted until the next rotation's first step replaces it; to drop it at
once, copy the new key over the ``~fleet_key_next`` files and run ``reload_keys``.
"""

import argparse
import concurrent.futures
import sys

import rosgraph
import rospy

from server_select.core.config.params import ParamError
from server_select.core.trust.senders import Throttle
from server_select.ros import seal

SERVICE = 'reload_keys'
_FAILED = Throttle(60.0)     # a failed reload's log line: one a minute (the caller is told)


def serve():
    """This node's ``~reload_keys`` (only with a key: without one there is nothing to
    read again)."""
    from server_select.srv import ReloadKeys
    return rospy.Service('~' + SERVICE, ReloadKeys, _reload)


def _reload(_request):
    from server_select.srv import ReloadKeysResponse
    try:
        before, after = seal.reload_keys()
    except ParamError as error:
        kept = seal.fingerprints()
        if _FAILED.due()[0]:
            rospy.logwarn('%s: reload_keys: keys kept (signs with %s, admits %s): %s',
                          rospy.get_name(), *_said(kept), error)
        return ReloadKeysResponse(False, 'keys kept: %s' % error, kept[0] or '', kept[1])
    if after != before:          # a call that changes nothing says nothing
        rospy.loginfo('%s: keys read again: signs with %s, admits %s (before: %s, %s)',
                      rospy.get_name(), *(_said(after) + _said(before)))
    return ReloadKeysResponse(True, 'changed' if after != before else 'unchanged',
                              after[0] or '', after[1])


def _said(prints):
    return prints[0] or 'nothing', ' and '.join(prints[1])


def nodes_serving(master):
    """The names of the services ``reload_keys`` registered on ``master``."""
    _, _, services = master.getSystemState()
    return sorted(name for name, _ in services if name.rsplit('/', 1)[-1] == SERVICE)


def call_all(names, timeout, master=None, at_once=8):
    """{service: its response, or the error's text} of one call to each of ``names``,
    ``at_once`` calls at a time (``master``: the rosgraph.Master they are registered on,
    asked first, one name after the other; None: this process's)."""
    from server_select.ros.probe_client import TimedServiceProxy
    from server_select.srv import ReloadKeys, ReloadKeysRequest
    where = {}
    for name in names:
        try:
            where[name] = master.lookupService(name) if master is not None else None
        except (OSError, rosgraph.MasterError) as error:
            where[name] = error

    def call(name):
        uri = where[name]
        if isinstance(uri, Exception):
            return str(uri) or type(uri).__name__
        proxy = TimedServiceProxy(name, ReloadKeys, pinned=uri and (lambda: uri))
        try:
            return proxy.call_within(ReloadKeysRequest(), timeout)[0]
        except rospy.ServiceException as error:
            return str(error) or type(error).__name__
        finally:
            proxy.close()
    with concurrent.futures.ThreadPoolExecutor(at_once) as pool:
        return dict(zip(names, pool.map(call, names)))


def report(answers):
    """(lines to print, whether every node answered, read its files, and agrees)."""
    lines, signs, admits = [], set(), set()
    for name, answer in sorted(answers.items()):
        if isinstance(answer, str):
            lines.append('%-40s no answer: %s' % (name, answer))
            continue
        lines.append('%-40s %-9s signs with %-12s admits %s%s' % (
            name, answer.message if answer.ok else 'FAILED', answer.signs or '-',
            ' '.join(answer.accepts), '' if answer.ok else '\n    ' + answer.message))
        if answer.signs:                 # (a node that only checks signs with none)
            signs.add(answer.signs)
        admits.add(tuple(sorted(answer.accepts)))
    ok = bool(answers) and all(not isinstance(a, str) and a.ok for a in answers.values())
    agree = len(signs) <= 1 and len(admits) <= 1
    if answers and not agree:
        lines.append('the nodes disagree: %d keys signed with, %d sets admitted' % (
            len(signs), len(admits)))
    return lines, ok and agree


def main(argv=None):
    """``reload_keys [--timeout S]``: every node's ``~reload_keys`` on this master."""
    parser = argparse.ArgumentParser(
        prog='reload_keys', description='Ask every node of the fleet to read its key files '
        '(~fleet_key, ~fleet_key_next) again, and print what each now signs with and admits '
        '(fingerprints). Exit status 1 when a node fails, does not answer, or disagrees.')
    parser.add_argument('--timeout', type=float, default=5.0, help='s for each node')
    args = parser.parse_args(rospy.myargv(sys.argv if argv is None else argv)[1:])
    try:
        names = nodes_serving(rosgraph.Master('/reload_keys'))
    except (OSError, rosgraph.MasterError) as error:
        parser.exit(2, 'reload_keys: no master at %s: %s\n' % (rosgraph.get_master_uri(),
                                                               error))
    if not names:
        parser.exit(1, 'reload_keys: no node serves %s (nodes with ~fleet_key do)\n' % SERVICE)
    lines, good = report(call_all(names, args.timeout))
    print('\n'.join(lines))
    return 0 if good else 1
