"""``docs/parameters.md``, made from the parameter table and the launch files (no rospy).

The table (:data:`server_select.core.settings.PARAMS` with the profiles' defaults) says
what each parameter means and what it defaults to; each role's launch file says which
parameters its node takes, under which launch argument. :func:`problems` lists where the
two disagree (a launch file setting a parameter the table does not have, an argument
that reaches nothing, a parameter no launch file or node list names); :func:`render` is
the document (``--check``: fail when the repository's is not what it makes; ``--write``).
"""

import argparse
import os
import re
import sys
import textwrap
import xml.etree.ElementTree as ET

from server_select.core.config import limits
from server_select.core.robot.tuning import LIVE, LIVE_DOC
from server_select.core.ranking.policy import POLICIES
from server_select.core.settings import PARAMS, PROFILES, REQUIRED
from server_select.ros.paths import package_file

TOP = package_file()       # the package's folder (the source tree: docs/ is not installed)
DOC = os.path.join('docs', 'parameters.md')
# the roles' launch files, in the document's order
ROLE_FILES = ('server.launch', 'robot.launch', 'manager.launch', 'top_manager.launch',
              'oracle.launch')
# Nodes started without a role launch file of their own, and the parameters they read.
OTHER_NODES = {
    'report': ('duration', 'output', 'end_launch', 'fleet_key', 'fleet_key_next'),
    'search_monitor': ('area', 'radius', 'timeout', 'output', 'end_launch'),
    'usage': ('nodes', 'delay', 'duration', 'output'),
}
# Launch arguments that are not node parameters.
LAUNCH_ONLY = {
    'output': 'where the node logs: screen or log',
    'machine': 'roslaunch machine to run on (empty: this host)',
    'name': "the node's name",
    'settings': 'a YAML file of more private parameters (e.g. a plug-in\'s settings), '
                'loaded with find and arg substitution',
}
# words of the policy argument's doc that are not policies
POLICY_DOC_WORDS = {'the', 'paper', 'fleet', 'or', 'peer', 'per', 'task', 'rule', 'rules'}
ARG = re.compile(r'\$\(arg ([A-Za-z_][A-Za-z0-9_]*)\)')
EVAL_ARG = re.compile(r"arg\('([A-Za-z_][A-Za-z0-9_]*)'\)")


def launch_path(name, top=TOP):
    return os.path.join(top, 'launch', name)


def read_launch(path):
    """``(args, params, used)``: the declared arguments ``{name: (default, doc)}``; for the
    package's node in the file, ``{parameter: argument}`` (None: not a plain
    ``$(arg ...)``); and the arguments its attributes and ``<rosparam>`` files use."""
    root = ET.parse(path).getroot()
    args = dict((a.get('name'), (a.get('default', a.get('value')), a.get('doc') or ''))
                for a in root.iter('arg'))
    params, used = {}, set()
    for node in root.iter('node'):
        if node.get('pkg') != 'server_select':
            continue
        for param in node.iter('param'):
            match = ARG.fullmatch(param.get('value', ''))
            params[param.get('name')] = match.group(1) if match else None
        texts = [node.get(k, '') for k in ('name', 'output', 'machine')]
        texts += [r.get('file', '') for r in node.iter('rosparam')]
        used.update(arg for text in texts for pattern in (ARG, EVAL_ARG)
                    for arg in pattern.findall(text))
    return args, params, used


def problems(top=TOP):
    """Where the table and the launch files disagree (empty: they agree)."""
    found, named = [], set()
    for name in ROLE_FILES:
        args, params, used = read_launch(launch_path(name, top))
        for param, arg in sorted(params.items()):
            named.add(param)
            if param not in PARAMS:
                found.append('%s: parameter %r is not in the table (core/settings.py)'
                             % (name, param))
            if arg is not None:
                used.add(arg)
                if arg not in args:
                    found.append('%s: parameter %r takes argument %r, which is not declared'
                                 % (name, param, arg))
        for arg in sorted(set(args) - used):
            found.append('%s: argument %r reaches no parameter of the node' % (name, arg))
        found += default_problems(name, args, params)
    for params in OTHER_NODES.values():
        named.update(params)
        found += ['node list: %r is not in the table' % p for p in params if p not in PARAMS]
    found += ['table: %r is set by no launch file and read by no listed node' % p
              for p in sorted(set(PARAMS) - named)]
    return found + listing_problems(top)


def default_problems(name, args, params):
    """A launch default that is not the node's: an argument is ``-`` (the node's default,
    in either profile), has none (the parameter is required), or is the table's default.
    The policy argument's doc names exactly the policies there are."""
    found = []
    for param, arg in sorted(params.items()):
        default = args.get(arg, ('-', ''))[0] if arg else '-'
        table = PARAMS[param].default if param in PARAMS else None
        if default == '-' or (default is None and table is REQUIRED) or \
                default == str(table):
            continue
        found.append('%s: argument %r defaults to %r, the node to %s' % (
            name, arg, default, value(table)))
    if 'policy' in args:
        named = set(re.findall(r'[a-z][a-z0-9_]+', args['policy'][1])) - POLICY_DOC_WORDS
        if named != set(POLICIES):
            found.append('%s: argument \'policy\' names %s; the policies are %s' % (
                name, sorted(named), sorted(POLICIES)))
    return found


def listing_problems(top=TOP):
    """Arguments ``roslaunch <file> --ros-args`` would list badly: without a doc, or with an
    empty default (roslaunch lists those as required: an argument left to the node's default
    has ``-``)."""
    found = []
    for name in sorted(os.listdir(os.path.join(top, 'launch'))):
        root = ET.parse(launch_path(name, top)).getroot()
        for arg in root.findall('arg'):
            if arg.get('value') is not None:
                continue
            if not arg.get('doc'):
                found.append('%s: argument %r has no doc' % (name, arg.get('name')))
            if arg.get('default') == '':
                found.append('%s: argument %r defaults to "" (roslaunch --ros-args lists it '
                             'as required): "-" leaves the node\'s default'
                             % (name, arg.get('name')))
    return found


def value(v):
    if v is REQUIRED:
        return 'required'
    if v is None:
        return '(see meaning)'
    if isinstance(v, bool):
        return '`%s`' % str(v).lower()
    if v == '':
        return "`''`"
    if isinstance(v, list):
        return '`[]`' if not v else '`%s`' % v
    return '`%s`' % (v,)


def row(param, arg=None):
    spec = PARAMS[param]
    fleet = PROFILES['fleet'].get(param, spec.default)
    cells = ['`~%s`' % param, value(spec.default),
             'same' if fleet == spec.default else value(fleet), spec.doc.replace('|', '\\|')]
    if arg is not None:
        cells.insert(0, '`%s`' % arg)
    return '| %s |' % ' | '.join(cells)


def render(top=TOP):
    """The document."""
    out = ['# Parameters', '',
           'Made by `python3 -m server_select.paramdoc --write` from the parameter table '
           '(`src/server_select/core/settings.py`) and the launch files; `make test` checks '
           'that it is current and that the two agree. Every parameter is private (`~name`). '
           'A launch argument left at `-` (the default of all but ids; empty is the same) leaves '
           'the node\'s default, the `paper` column or, with `profile:=fleet`, the `fleet` '
           'column; a parameter set explicitly always wins. Id lists are YAML lists or strings: '
           '`[1, 2, 3]`, `"1,2,3"`, `"1 2 3"`. An invalid value stops the node with one '
           '`invalid parameter` line and exit status 2.', '']
    for name in ROLE_FILES:
        args, params, _ = read_launch(launch_path(name, top))
        node = os.path.splitext(name)[0]
        out += ['## `%s` (`roslaunch server_select %s`)' % (node, name), '',
                '| launch argument | parameter | paper | fleet | meaning |',
                '|---|---|---|---|---|']
        out += [row(param, arg or '(fixed)') for param, arg in params.items()]
        others = [a for a in args if a not in params.values()]
        out += ['| `%s` | – | %s | same | %s |' % (a, '`%s`' % args[a][0] if args[a][0]
                                                   not in ('', '-') else '(none)',
                                                   LAUNCH_ONLY.get(a) or args[a][1])
                for a in others]
        out.append('')
    out += ['## Other nodes', '', '| node | parameter | paper | fleet | meaning |',
            '|---|---|---|---|---|']
    for node, params in OTHER_NODES.items():
        out += [row(p).replace('| ', '| `%s` | ' % node, 1) for p in params]
    out += ['', '## Live on a running robot', '', LIVE_DOC % ', '.join('`%s`' % n for n in LIVE),
            '', '## Message size limits', ''] + limits.table()
    return '\n'.join(out) + '\n'


def node_params(node, top=TOP):
    """The parameters node type ``node`` (``robot``, ``report``, ...) reads, in the order
    its launch file (or node list) gives them."""
    if node in OTHER_NODES:
        return list(OTHER_NODES[node])
    return list(read_launch(launch_path(node + '.launch', top))[1])


def usage(node, summary='', top=TOP):
    """What ``rosrun server_select <node> --help`` prints: the node's parameters with
    their defaults in both profiles and their meaning."""
    out = ['usage: rosrun server_select %s [_parameter:=value ...] [__name:=name]' % node,
           '       roslaunch server_select %s.launch [argument:=value ...]' % node
           if node not in OTHER_NODES else '', '',
           ' '.join((summary or '').split('\n\n')[0].split()), '',
           'parameters (default; with ~profile fleet, when another):']
    for name in node_params(node, top):
        spec = PARAMS[name]
        default = value(spec.default).strip('`')
        fleet = PROFILES['fleet'].get(name, spec.default)
        if fleet != spec.default:
            default += '; fleet: ' + value(fleet).strip('`')
        out.append('  ~%-22s %s' % (name, default))
        out += textwrap.wrap(spec.doc, 96, initial_indent=' ' * 26,
                             subsequent_indent=' ' * 26)
    out += ['', 'docs/parameters.md has them all; every launch argument of a launch file: '
            'roslaunch server_select <file>.launch --ros-args']
    return '\n'.join(line for i, line in enumerate(out) if line or i != 1)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument('--write', action='store_true', help='write %s' % DOC)
    group.add_argument('--check', action='store_true', help='fail unless it is current')
    args = parser.parse_args(argv)
    found = problems()
    for line in found:
        print('paramdoc: %s' % line, file=sys.stderr)
    path = os.path.join(TOP, DOC)
    text = render()
    if args.write:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, 'w') as stream:
            stream.write(text)
    elif not os.path.exists(path) or open(path).read() != text:
        print('paramdoc: %s is not current: run python3 -m server_select.paramdoc --write'
              % DOC, file=sys.stderr)
        return 1
    return 1 if found else 0


if __name__ == '__main__':
    sys.exit(main())
