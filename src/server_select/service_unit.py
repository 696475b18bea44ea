"""``rosrun server_select install_service ROLE [arg:=value ...]``: a systemd unit that starts
one role of the fleet on this host at boot and keeps it running.

A fleet's hosts run their roles without anyone logged in: each host starts its role when it
boots, waits for the master (``roslaunch --wait``, so the order hosts come up in does not
matter) and is started again when it ends (``Restart=always``), so one host that is down
stops nothing on the others. The unit runs ``scripts/env_loader.sh`` (it sources this
package's setup and sets ``ROS_IP``) and then ``roslaunch --wait server_select
<role>.launch`` with the given arguments; ``roscore`` runs the master itself. ``systemctl
stop`` sends SIGINT to every process of the unit, which is a Ctrl-C for roslaunch and each
node.

    sudo rosrun server_select install_service robot robot_id:=3 profile:=fleet \\
        --master http://192.168.1.10:11311 --ros-ip 192.168.1.23 --user pi --enable
"""

import argparse
import os
import re
import shlex
import subprocess
import sys
import urllib.parse

ROLES = ('roscore', 'manager', 'server', 'robot', 'top_manager')
ID_ARGS = {'robot': 'robot_id', 'server': 'server_id', 'manager': 'group'}
ARG = re.compile(r'^[A-Za-z_][A-Za-z0-9_]*:=.*$')


def unit_name(role, args):
    """``server_select-<role>[-<id>]``: one unit per role and id on a host."""
    key = ID_ARGS.get(role)
    ident = next((a.split(':=', 1)[1] for a in args if key and a.startswith(key + ':=')), '')
    ident = re.sub(r'[^A-Za-z0-9_.-]', '_', ident)
    return 'server_select-%s%s' % (role.replace('_', '-'), '-' + ident if ident else '')


def command(role, args, loader, master):
    """The unit's command line (a list)."""
    if role == 'roscore':
        port = urllib.parse.urlparse(master).port or 11311
        return [loader, 'roscore', '-p', str(port)]
    return [loader, 'roslaunch', '--wait', 'server_select', '%s.launch' % role] + list(args)


def unit_text(role, args, loader, master, ros_ip=None, user=None, ros_home=None):
    """The text of the systemd unit (see the module's docstring)."""
    if role not in ROLES:
        raise ValueError('unknown role %r (expected one of %s)' % (role, ', '.join(ROLES)))
    bad = [a for a in args if not ARG.match(a)]
    if bad:
        raise ValueError('launch arguments are name:=value, got %s' % ' '.join(bad))
    if not urllib.parse.urlparse(master).hostname:
        raise ValueError('--master must be a URI such as http://192.168.1.10:11311, got %r'
                         % master)
    # unbuffered: the journal gets each log line when it is written
    env = [('ROS_MASTER_URI', master)] + ([('ROS_IP', ros_ip)] if ros_ip else []) + \
        ([('ROS_HOME', ros_home)] if ros_home else []) + [('PYTHONUNBUFFERED', '1')]
    lines = ['[Unit]',
             'Description=server_select %s %s' % (role, ' '.join(args)),
             'Wants=network-online.target',
             'After=network-online.target',
             '',
             '[Service]',
             'Type=simple']
    lines += ['User=%s' % user] if user else []
    lines += ['Environment=%s' % shlex.quote('%s=%s' % kv) for kv in env]
    lines += ['ExecStart=%s' % ' '.join(_escape(shlex.quote(part)) for part in
                                        command(role, args, loader, master)),
              'Restart=always',
              'RestartSec=5',
              'KillSignal=SIGINT',
              'TimeoutStopSec=20',
              '',
              '[Install]',
              'WantedBy=multi-user.target',
              '']
    return '\n'.join(lines)


def _escape(text):
    """``%`` and ``$`` as systemd reads them literally in ExecStart."""
    return text.replace('%', '%%').replace('$', '$$')


def parse_unit(text):
    """``(environment dict, command list, {key: value})`` of a unit written by
    :func:`unit_text` (what systemd would run)."""
    env, keys = {}, {}
    for line in text.splitlines():
        if '=' not in line or line.startswith('['):
            continue
        key, value = line.split('=', 1)
        if key == 'Environment':
            name, _, setting = shlex.split(value)[0].partition('=')
            env[name] = setting
        else:
            keys[key] = value
    execute = keys['ExecStart'].replace('$$', '\0').replace('%%', '%').replace('\0', '$')
    return env, shlex.split(execute), keys


def default_loader():
    """This package's ``env_loader.sh`` (source tree, devel or install space)."""
    from roslib.packages import find_resource
    found = find_resource('server_select', 'env_loader.sh')
    if not found:
        raise RuntimeError('env_loader.sh of server_select not found (is the package\'s '
                           'setup.bash sourced?)')
    return os.path.abspath(found[0])


def main(argv=None):
    parser = argparse.ArgumentParser(prog='install_service',
                                     description=__doc__.split('\n\n')[0])
    parser.add_argument('role', choices=ROLES)
    parser.add_argument('args', nargs='*', help='launch arguments, name:=value')
    parser.add_argument('--master', default=os.environ.get('ROS_MASTER_URI',
                                                           'http://localhost:11311'),
                        help='ROS_MASTER_URI of the fleet (default: this shell\'s)')
    parser.add_argument('--ros-ip', default=os.environ.get('ROS_IP'),
                        help='the address other hosts reach this one at (default: this '
                        'shell\'s ROS_IP, else the env loader\'s guess)')
    parser.add_argument('--user', help='run as this user (default: root)')
    parser.add_argument('--ros-home', help='ROS_HOME of the role (logs)')
    parser.add_argument('--loader', help='the environment loader (default: this package\'s '
                        'scripts/env_loader.sh)')
    parser.add_argument('--unit-dir', default='/etc/systemd/system',
                        help='where to write the unit file (default: %(default)s)')
    parser.add_argument('--print', action='store_true', help='print the unit, write nothing')
    parser.add_argument('--enable', action='store_true',
                        help='systemctl daemon-reload, then enable --now the unit')
    opts = parser.parse_args(argv)
    try:
        text = unit_text(opts.role, opts.args, opts.loader or default_loader(), opts.master,
                         opts.ros_ip, opts.user, opts.ros_home)
    except (ValueError, RuntimeError) as error:
        parser.error(str(error))
    if opts.print:
        sys.stdout.write(text)
        return 0
    name = unit_name(opts.role, opts.args)
    path = os.path.join(opts.unit_dir, name + '.service')
    with open(path, 'w') as stream:
        stream.write(text)
    print('wrote %s' % path)
    if opts.enable:
        for cmd in (['systemctl', 'daemon-reload'], ['systemctl', 'enable', '--now', name]):
            subprocess.check_call(cmd)
        print('%s enabled and started; its log: journalctl -u %s' % (name, name))
    else:
        print('start it now and at every boot: systemctl daemon-reload && systemctl enable '
              '--now %s' % name)
    return 0
