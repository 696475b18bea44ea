"""The systemd unit of ``install_service`` (service_unit.py): what it runs, as what, how it
stops and restarts, and what it refuses."""

import pytest

from server_select.service_unit import main, parse_unit, unit_name, unit_text

MASTER = 'http://192.168.1.10:11311'
LOADER = '/home/pi/server_select/scripts/env_loader.sh'


def test_a_robot_unit_waits_for_the_master_and_restarts_always():
    text = unit_text('robot', ['robot_id:=3', 'profile:=fleet', 'servers:=[]'], LOADER, MASTER,
                     ros_ip='192.168.1.23', user='pi')
    env, cmd, keys = parse_unit(text)
    assert env == {'ROS_MASTER_URI': MASTER, 'ROS_IP': '192.168.1.23', 'PYTHONUNBUFFERED': '1'}
    assert cmd == [LOADER, 'roslaunch', '--wait', 'server_select', 'robot.launch',
                   'robot_id:=3', 'profile:=fleet', 'servers:=[]']
    assert (keys['User'], keys['Restart'], keys['KillSignal']) == ('pi', 'always', 'SIGINT')
    assert keys['WantedBy'] == 'multi-user.target' and keys['After'] == 'network-online.target'
    assert unit_name('robot', ['profile:=fleet', 'robot_id:=3']) == 'server_select-robot-3'


def test_the_master_host_runs_roscore_on_the_masters_port():
    env, cmd, _ = parse_unit(unit_text('roscore', [], LOADER, 'http://10.0.0.1:11411'))
    assert cmd == [LOADER, 'roscore', '-p', '11411'] and 'ROS_IP' not in env
    assert unit_name('roscore', []) == 'server_select-roscore'
    assert unit_name('top_manager', []) == 'server_select-top-manager'
    assert unit_name('manager', ['group:=2']) == 'server_select-manager-2'


def test_specifiers_and_spaces_reach_the_command_as_written():
    args = ['settings:=/home/pi/my settings.yaml', 'image_topic:=/cam$1', 'name:=50%']
    text = unit_text('robot', ['robot_id:=1'] + args, LOADER, MASTER)
    assert '%%' in text and '$$' in text          # systemd's own escapes
    assert parse_unit(text)[1][-3:] == args


@pytest.mark.parametrize('role, args, master, why', [
    ('robots', [], MASTER, 'unknown role'),
    ('robot', ['robot_id=3'], MASTER, 'name:=value'),
    ('robot', ['robot_id:=3'], '192.168.1.10', 'must be a URI'),
])
def test_bad_requests_are_refused(role, args, master, why):
    with pytest.raises(ValueError, match=why):
        unit_text(role, args, LOADER, master)


def test_the_command_writes_the_unit_and_says_how_to_enable_it(tmp_path, capsys):
    assert main(['server', 'server_id:=4', 'profile:=fleet', '--master', MASTER,
                 '--loader', LOADER, '--unit-dir', str(tmp_path)]) == 0
    path = tmp_path / 'server_select-server-4.service'
    _, cmd, _ = parse_unit(path.read_text())
    assert cmd[4:] == ['server.launch', 'server_id:=4', 'profile:=fleet']
    assert 'systemctl daemon-reload && systemctl enable --now server_select-server-4' \
        in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(['server', 'server_id=4', '--loader', LOADER, '--unit-dir', str(tmp_path)])
