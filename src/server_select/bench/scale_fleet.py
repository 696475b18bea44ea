"""The processes of a scale run (:mod:`server_select.bench.scale`): the manager node(s)
under test, the simulated robots (:mod:`server_select.bench.scale_sim`), and what those
write (first full rankings, sample-to-flag delays, flags received)."""

import json
import os
import subprocess
import sys

from server_select.bench.harness import PY
from server_select.bench.scale_layout import group_table


def start_node(module, args, log):
    cmd = [sys.executable, '-c', 'from server_select.nodes.%s import main; main()' % module]
    with open(log, 'a') as stream:
        return subprocess.Popen(cmd + args, stdout=stream, stderr=subprocess.STDOUT,
                                start_new_session=True)


def start_managers(layout, robots, servers, groups, log, profile='paper', key=None,
                   flag_stream='shared'):
    """The nodes under test: {node name: process}."""
    ids = ','.join(map(str, range(1, servers + 1)))
    common = ["_robot_node:='*'", '_discover:=false', '_profile:=%s' % profile,
              '_flag_stream:=%s' % flag_stream] + (['_fleet_key:=%s' % key] if key else [])
    if layout != 'grouped':
        return {'/manager': start_node('manager', common + [
            '_robots:=%s' % ','.join(map(str, range(1, robots + 1))), '_servers:=%s' % ids,
            '_sample_stream:=%s' % layout, '__name:=manager'], log)}
    table = group_table(servers, groups)
    nodes = {'/top_manager': start_node('top_manager', common + [
        '_groups:=%s' % json.dumps(dict((str(g), s) for g, s in table.items())),
        '__name:=top_manager'], log)}
    for group in table:
        nodes['/manager_g%d' % group] = start_node('manager', common + [
            '_robots:=[]', '_servers:=[]', '_sample_stream:=robot', '_group:=%d' % group,
            '__name:=manager_g%d' % group], log)
    return nodes


def start_sims(tmp, robots, servers, sims, layout, until, log, groups=1, rate=1.0, key=None,
               flag_stream='shared'):
    """The simulated robots' processes: {node name: (process, its result file)}."""
    per = -(-robots // sims)
    started = {}
    for first in range(1, robots + 1, per):
        out = os.path.join(tmp, 'sim%d.json' % first)
        cmd = PY + ['server_select.bench.scale_sim', '--first', str(first), '--count',
                    str(min(per, robots - first + 1)), '--servers', str(servers),
                    '--layout', layout, '--until', repr(until), '--out', out,
                    '--groups', str(groups), '--rate', repr(rate),
                    '--flag-stream', flag_stream] + \
            (['--fleet-key', key] if key else [])
        with open(log, 'a') as stream:
            started['/scale_sim_%d' % first] = (subprocess.Popen(
                cmd, stdout=stream, stderr=subprocess.STDOUT, start_new_session=True), out)
    return started


def sim_results(outs):
    """The simulated robots' result files so far (None while one is not written yet)."""
    results = []
    for out in outs:
        try:
            with open(out) as stream:
                results.append(json.load(stream))
        except FileNotFoundError:
            return None
    return results


def sim_progress(outs):
    """(latest first-full-ranking time over every robot, or None while one has none yet;
    the sample-to-flag delays) from the simulated robots' result files so far."""
    results = sim_results(outs)
    if results is None:
        return None, []
    ranked = [t for data in results for t in data['ranked'].values()]
    robots = sum(data['robots'] for data in results)
    delays = [d for data in results for d in data['delays']]
    return (max(ranked) if len(ranked) == robots and ranked else None), delays


def sim_received(outs):
    """(flags, bytes) that reached the simulated robots so far."""
    return [sum(d[k] for d in sim_results(outs) or []) for k in ('received', 'received_bytes')]
