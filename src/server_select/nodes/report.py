"""Listens to a run for ``~duration`` seconds, then prints the per-robot summary."""

import json
import os

import rospy

from server_select.core.config import names
from server_select.core.flow.outcome import cut_off
from server_select.core.config.params import parse_id_list
from server_select.core.observe.summary import RunReport
from server_select.msg import LatencySample, LatencySamples, SelectionFlag, TaskReport
from server_select.ros.node import end_parent_launch, fleet, param
from server_select.ros.runner import run
from server_select.ros.senders import FIRST, SenderGate, robot_senders


class ReportNode(object):
    """Run summary for demos and evaluations.

    :ROS Parameters:
        - ``~duration`` (s, 30.0): how long to listen before printing and exiting.
        - ``~output`` (str, ''): also write the summary as JSON to this path.
        - ``~task_timeout`` (s, 2.0): a failed task counts in the round-trip statistics at
          this (the robots' task timeout).
        - ``~end_launch`` (bool, false): then end the roslaunch that started this node
          cleanly, as Ctrl-C would (the timed demo's end).
        - ``~robots``, ``~servers`` (id lists, optional): also summarise the probe samples
          of these pairs.
    :ROS Subscribers:
        - ``server_select_flag`` (server_select/SelectionFlag)
        - ``task_report`` (server_select/TaskReport)
        - ``latency_R<r>S<s>`` (server_select/LatencySample), with ``~robots``/``~servers``
        - ``latency_samples`` (server_select/LatencySamples): the fleet profile's batches
    """

    def __init__(self):
        duration = param('duration')
        self.output = param('output')
        self.end_launch = param('end_launch')
        self.report = RunReport(param('task_timeout'))
        self.gate = SenderGate('report', 'a node of the fleet')   # with a key: sealed only
        self.robots = robot_senders('report', FIRST)       # a robot's reports: its own
        self.flag_sub = rospy.Subscriber(fleet(names.SELECTION_TOPIC), SelectionFlag, self.on_flag,
                                         queue_size=100)
        self.task_sub = rospy.Subscriber(fleet(names.TASK_REPORT_TOPIC), TaskReport, self.on_task,
                                         queue_size=1000)
        optional = dict(default='', parse=lambda n, v: parse_id_list(n, v) if v != '' else [])
        self.probe_subs = [
            rospy.Subscriber(fleet(names.sample_topic(r, s)), LatencySample, self.on_probe,
                             queue_size=100)
            for r in param('robots', **optional) for s in param('servers', **optional)]
        self.probe_subs.append(rospy.Subscriber(fleet(names.SAMPLES_TOPIC), LatencySamples,
                                                self.on_probes, queue_size=100))
        self.timer = rospy.Timer(rospy.Duration(duration), self.finish, oneshot=True)
        rospy.loginfo('report: listening for %.3g s', duration)

    def on_flag(self, flag):
        if not self.gate.admits(flag, 'a flag'):
            return
        self.report.add_flag(flag.robot_id, flag.server_id, flag.ranking, flag.mean_latency)

    def on_probe(self, sample):
        if not self.robots.admits(sample, 'a probe sample', sample.robot_id):
            return
        self.report.add_probe(sample.robot_id, sample.server_id, sample.ok, sample.rtt)

    def on_probes(self, batch):
        if not self.robots.admits(batch, 'probe samples', batch.robot_id):
            return
        for server, ok, rtt in zip(batch.server_id, batch.ok, batch.rtt):
            self.report.add_probe(batch.robot_id, server, ok, rtt)

    def on_task(self, report):
        if not self.robots.admits(report, 'a task report', report.robot_id):
            return
        if cut_off(report.error):       # a robot stopped with it out: not the fleet's doing
            return
        self.report.add_task(report.robot_id, report.ok, report.rtt, report.answered_by,
                             report.error, report.task_id, report.server_id, report.kind)

    def finish(self, _event=None):
        summaries = self.report.summaries()   # one moment for the table and the verdict
        table = self.report.table(summaries)
        text = ('\nserver_select run summary (a failed task counts at the task timeout, %g s)'
                '\n\n' % self.report.timeout + table + '\n\n' + self.report.legend() +
                '\n\nfound: ' + self.report.verdict(summaries) + '\n')
        print(text, flush=True)
        if self.output:
            with open(self.output, 'w') as stream:
                json.dump(summaries, stream, indent=2)
            with open(os.path.splitext(self.output)[0] + '.md', 'w') as stream:
                stream.write(text)      # (make demo prints it again after the shutdown lines)
            rospy.loginfo('report: summary written to %s', self.output)
        if not (self.end_launch and end_parent_launch()):
            rospy.signal_shutdown('report done')


def main():
    run('report', ReportNode)
