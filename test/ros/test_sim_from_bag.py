"""A recorded run as a simulated scenario: probe samples in a bag (the fleet's batches, the
paper's per-pair samples) become each pair's link and say which server left, task reports
the robots' rates and the measured part; the bag's own figures beside it."""

import math

import rosbag
import rospy

from server_select.msg import LatencySample, LatencySamples, TaskReport
from server_select.sim import from_bag
from server_select.sim.model import Model
from server_select.testbed.bag_analysis import load
from server_select.testbed.scenario import Scenario


def test_a_bag_of_probe_samples_becomes_a_scenario(tmp_path):
    path = str(tmp_path / 'run.bag')
    with rosbag.Bag(path, 'w') as bag:
        for n in range(40):               # 4 s: robot 1's batches, 10 a second
            t = rospy.Time(100 + 0.1 * n)
            ok = not 20 <= n < 25          # server 2 fails from 2.0 to 2.5 s
            bag.write('/latency_samples', LatencySamples(
                robot_id=1, round=n, server_id=[1, 2], ok=[True, ok],
                rtt=[0.0100 if n < 10 else 0.0200, 0.0060 if ok else 0.0]), t)
            bag.write('/robot2/latency_R2S1', LatencySample(robot_id=2, server_id=1,
                                                            ok=True, rtt=0.008), t)
            if n % 5 == 0:
                bag.write('/task_report', TaskReport(robot_id=1, task_id=n // 5 + 1,
                                                     server_id=1, kind='sort', ok=n != 35,
                                                     rtt=0.01), t)
    model = Model.load()
    run = load(path)
    data = from_bag.scenario(run, model)
    sc = Scenario(data, 'bag')           # a file the testbed and the simulator both read
    # its middleware is the model's (its round trips are longer than the model's part)
    assert data['suite']['hop_ms'] == 1e3 * model.hop
    overhead_ms = 1e3 * (2 * model.hop + model.probe_cpu) / 2.0
    assert sorted(h.id for h in sc.of_role('server')) == [1, 2]
    assert math.isclose(sc.link('robot1', 'server1', 0.5).delay, 5.0 - overhead_ms)
    assert not sc.link('robot1', 'server1', 0.5).down      # a pair with samples is up
    assert math.isclose(sc.link('robot1', 'server1', 1.5).delay, 10.0 - overhead_ms)
    assert sc.link('robot1', 'server2', 2.2).down and not sc.link('robot1', 'server2', 2.6).down
    assert sc.link('robot2', 'server2', 1.0).down          # never probed: no link
    assert data['suite']['measure_from'] == 0.0     # its first task was sent at 0 s
    assert math.isclose(data['suite']['robot_args']['task_rate'], 8 / 2 / 3.9, rel_tol=0.01)
    own = from_bag.recorded(run, data['suite']['measure_from'])
    assert own['tasks'] == 8 and own['failed'] == 1 and own['switches'] == 0.0
    assert math.isclose(own['mean'], (7 * 0.01 + 2.0) / 8)


def test_a_server_that_stops_answering_for_good_leaves_and_a_late_one_joins(tmp_path):
    path = str(tmp_path / 'run.bag')
    with rosbag.Bag(path, 'w') as bag:
        for n in range(100):               # 10 s of batches, 10 a second
            t = rospy.Time(100 + 0.1 * n)
            bag.write('/robot1/latency_samples', LatencySamples(
                robot_id=1, round=n, server_id=[1, 2, 3], ok=[True, n < 45, n >= 60],
                rtt=[0.0005, 0.0005, 0.0005]), t)
    data = from_bag.scenario(load(path), Model.load())
    hosts = Scenario(data, 'bag').hosts
    assert hosts['server2'].stop == 4.5 and hosts['server2'].start == 0.0
    assert hosts['server3'].start == 6.0 and hosts['server3'].stop is None
    assert hosts['server1'].stop is None
    # a run on one host: its middleware from its own round trips
    assert data['suite']['hop_ms'] < 1e3 * Model.load().hop


def test_a_bag_is_simulated_with_its_own_profile_first():
    """A fleet profile's manager records its server list, a paper one's does not: simulate
    --from-bag puts that profile's variant first unless --variants says otherwise."""
    from server_select.sim.cli import own_profile
    from server_select.testbed.bag_analysis import Run, Servers
    assert own_profile(Run({}, [], [], [], [Servers(1.0, [1, 2])])) == 'fleet'
    assert own_profile(Run({}, [], [], [], [])) == 'paper'
