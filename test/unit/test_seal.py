"""Signed fleet messages: key files, seals, replay and rotation (server_select.core.trust.seal)."""

import os
import stat

import pytest
from hypothesis import given, strategies as st

from server_select.core.trust import keys as key_files

from server_select.core.trust import seal

KEY, NEXT, OTHER = (seal.Keys.from_fleet(secret, 'manager')
                    for secret in (b'k' * 32, b'n' * 32, b'o' * 32))


class Clock(object):
    def __init__(self, now=10 ** 18):
        self.now = now

    def __call__(self):
        return self.now


def signed(key, sender, payload, clock):
    sealer = seal.Sealer(key, sender, clock)
    seq = sealer.next_seq()
    return seq, sealer.mac(seq, payload)


def test_a_message_sealed_with_the_key_counts_once():
    clock = Clock()
    verifier = seal.Verifier([KEY], max_age=30.0, clock=clock)
    seq, mac = signed(KEY, '/manager', b'flag', clock)
    assert verifier.refusal('/manager', seq, mac, b'flag') is None
    assert 'replayed' in verifier.refusal('/manager', seq, mac, b'flag')


def test_unsigned_wrong_key_other_content_or_other_name_are_refused():
    clock = Clock()
    verifier = seal.Verifier([KEY], clock=clock)
    seq, mac = signed(KEY, '/manager', b'flag', clock)
    assert verifier.refusal('/manager', seq, b'', b'flag') == 'not signed'
    assert verifier.refusal('/manager', seq, mac, b'flag!').startswith('wrong signature')
    assert verifier.refusal('/impostor', seq, mac, b'flag').startswith('wrong signature')
    assert verifier.refusal('/manager', seq + 1, mac, b'flag').startswith('wrong signature')
    seq, mac = signed(OTHER, '/manager', b'flag', clock)
    assert verifier.refusal('/manager', seq, mac, b'flag').startswith('wrong signature')


def test_a_copy_on_another_topic_or_as_another_type_is_refused():
    clock = Clock()
    verifier = seal.Verifier([KEY], clock=clock)
    sealer = seal.Sealer(KEY, '/robot1', clock)
    flag = seal.context('/robot_1/server_select_flag', 'server_select/SelectionFlag')
    seq = sealer.next_seq()
    mac = sealer.mac(seq, b'x', flag)
    for where in (seal.context('/robot_2/server_select_flag', 'server_select/SelectionFlag'),
                  seal.context('/robot_1/server_select_flag', 'server_select/Other'), b''):
        assert verifier.refusal('/robot1', seq, mac, b'x', where).startswith('wrong')
    assert verifier.refusal('/robot1', seq, mac, b'x', flag) is None


def test_a_receiver_that_restarted_refuses_what_was_sent_before_it_started():
    clock = Clock()
    seq, mac = signed(KEY, '/manager', b'flag', clock)
    clock.now += int(seal.START_SKEW * 1e9) + 1           # well within max_age (30 s)
    restarted = seal.Verifier([KEY], max_age=30.0, clock=clock, monotonic=Clock(0))
    assert 'before this node started' in restarted.refusal('/manager', seq, mac, b'flag')
    seq, mac = signed(KEY, '/manager', b'flag', clock)     # what is sent now counts
    assert restarted.refusal('/manager', seq, mac, b'flag') is None
    # within the skew the fleet's clocks may have: counts
    clock.now += int(1e9)
    seq, mac = signed(KEY, '/manager', b'flag', lambda: clock.now - int(1.5e9))
    assert seal.Verifier([KEY], clock=clock).refusal('/manager', seq, mac, b'flag') is None


def test_a_recording_replayed_later_is_refused_even_by_a_receiver_that_never_saw_it():
    clock = Clock()
    seq, mac = signed(KEY, '/manager', b'flag', clock)
    clock.now += int(31e9)
    fresh = seal.Verifier([KEY], max_age=30.0, clock=clock)
    why = fresh.refusal('/manager', seq, mac, b'flag')
    assert why.startswith('signed 31.0 s before')
    clock.now -= int(62e9)                        # a sender whose clock runs ahead
    assert fresh.refusal('/manager', seq, mac, b'flag').startswith(
        "this host's clock is 31.0 s behind /manager's: check NTP")


def test_a_sender_whose_clock_is_stepped_back_is_heard_again_at_once():
    """A Pi without a real-time clock boots 120 s ahead; NTP steps it back. Its sequence
    numbers follow the clock back, rather than counting on from the skewed time."""
    true = Clock()
    robot_clock = Clock(true.now + int(120e9))
    sealer = seal.Sealer(KEY, '/robot1', robot_clock)
    server = seal.Verifier([KEY], clock=true)
    seq = sealer.next_seq()
    why = server.refusal('/robot1', seq, sealer.mac(seq, b'p'), b'p')
    assert why.startswith("this host's clock is 120.0 s behind /robot1's: check NTP"), why
    true.now += int(1e9)
    robot_clock.now = true.now                   # the step back
    seq = sealer.next_seq()
    assert server.refusal('/robot1', seq, sealer.mac(seq, b'p'), b'p') is None
    small = seal.Sealer(KEY, '/robot2', true)    # a step back within CLOCK_STEP: counts on
    first = small.next_seq()
    true.now -= int(0.5e9)
    assert small.next_seq() == first + 1


def test_a_receiver_whose_clock_is_stepped_back_hears_the_fleet_again_at_once():
    """Its start moves with its clock: a node that started 120 s ahead refused every
    message as signed before it started until real time caught up."""
    true, mono = Clock(), Clock(5 * 10 ** 9)
    robot_clock = Clock(true.now + int(120e9))
    robot = seal.Verifier([KEY], clock=robot_clock, monotonic=mono)
    true.now += int(3e9)
    mono.now += int(3e9)
    robot_clock.now = true.now                   # the step back, 3 s after it started
    seq, mac = signed(KEY, '/server3', b'answer', true)
    assert robot.refusal('/server3', seq, mac, b'answer') is None
    old_seq, old_mac = signed(KEY, '/server3', b'answer', lambda: true.now - int(6e9))
    assert 'before this node started' in robot.refusal('/server3', old_seq, old_mac, b'answer')


def test_messages_that_arrive_out_of_order_count_each_once():
    clock = Clock()
    sealer = seal.Sealer(KEY, '/robot1', clock)
    sealed = [(s, sealer.mac(s, b'x')) for s in (sealer.next_seq() for _ in range(5))]
    verifier = seal.Verifier([KEY], clock=clock)
    for seq, mac in reversed(sealed):             # two threads may publish in either order
        assert verifier.refusal('/robot1', seq, mac, b'x') is None
    assert all(verifier.refusal('/robot1', s, m, b'x') for s, m in sealed)


@given(st.lists(st.integers(min_value=-5, max_value=5), min_size=1, max_size=50))
def test_sequence_numbers_strictly_increase_while_the_clock_runs_on(steps):
    clock = Clock()
    sealer = seal.Sealer(KEY, '/n', clock)
    seqs = []
    for step in steps:
        clock.now += step
        seqs.append(sealer.next_seq())
    assert all(a < b for a, b in zip(seqs, seqs[1:]))


def test_what_is_remembered_is_bounded_by_the_age_limit():
    clock = Clock()
    sealer = seal.Sealer(KEY, '/robot1', clock)
    verifier = seal.Verifier([KEY], max_age=1.0, clock=clock)
    for _ in range(100):
        clock.now += int(0.1e9)
        seq = sealer.next_seq()
        assert verifier.refusal('/robot1', seq, sealer.mac(seq, b''), b'') is None
    assert len(verifier._seen['/robot1']) <= 11


def test_rotation_accepts_the_next_key_and_the_current_one():
    clock = Clock()
    verifier = seal.Verifier([KEY, NEXT], clock=clock)
    for key in (KEY, NEXT):
        seq, mac = signed(key, '/manager', b'flag', clock)
        assert verifier.refusal('/manager', seq, mac, b'flag') is None
        clock.now += 1
    seq, mac = signed(OTHER, '/manager', b'flag', clock)
    assert verifier.refusal('/manager', seq, mac, b'flag').startswith('wrong signature')


def test_a_rotation_in_place_moves_signer_and_verifier_and_keeps_replays_refused():
    """Stage (accept the next key too), swap (sign with it), retire (only it): no
    sequence number goes back, and a message seen before the swap stays a replay."""
    clock = Clock()
    sealer, verifier = seal.Sealer(KEY, '/manager', clock), seal.Verifier([KEY], clock=clock)
    seq = sealer.next_seq()
    before = (seq, sealer.mac(seq, b'flag'))
    assert verifier.refusal('/manager', *before, payload=b'flag') is None
    verifier.use([KEY, NEXT])                                       # stage
    sealer.use(NEXT)                                                # swap
    clock.now -= 5                       # the clock stepped back within CLOCK_STEP
    after = sealer.next_seq()
    assert after > seq
    assert verifier.refusal('/manager', after, sealer.mac(after, b'flag'), b'flag') is None
    assert 'replayed' in verifier.refusal('/manager', *before, payload=b'flag')
    verifier.use([NEXT])                                            # retire
    old = signed(KEY, '/manager', b'flag', clock)
    assert verifier.refusal('/manager', *old, payload=b'flag').startswith('wrong signature')
    with pytest.raises(ValueError):
        verifier.use([])
    with pytest.raises(ValueError):          # another role's key: the node's role is fixed
        sealer.use(seal.Keys.from_fleet(b'n' * 32, 'robot'))


def test_a_fingerprint_names_the_fleet_whatever_file_holds_its_keys(tmp_path):
    fleet = str(tmp_path / 'fleet.key')
    key_files.make_key(fleet)
    role = str(tmp_path / 'robot.key')
    key_files.make_role_key(fleet, 'robot', role)
    prints = set(key_files.load_keys(path, r).fingerprint()
                 for path, r in ((fleet, None), (fleet, 'manager'), (role, 'robot'), (role, None)))
    assert len(prints) == 1 and len(prints.pop()) == 12
    assert KEY.fingerprint() != NEXT.fingerprint()


def test_make_key_writes_a_private_key_that_loads_and_keeps_an_existing_file(tmp_path):
    path = str(tmp_path / 'fleet.key')
    key_files.make_key(path)
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o600
    key = key_files.load_key(path)
    assert len(key) == key_files.KEY_BYTES
    with pytest.raises(FileExistsError):
        key_files.make_key(path)
    assert key_files.load_key(path) == key
    assert key_files.make_key_cli([str(tmp_path / 'second.key')]) == 0
    assert key_files.load_key(str(tmp_path / 'second.key')) != key


@pytest.mark.parametrize('mode', [0o640, 0o604, 0o620, 0o666])
def test_a_key_others_can_read_or_write_is_refused_with_what_to_do(tmp_path, mode):
    path = str(tmp_path / 'fleet.key')
    key_files.make_key(path)
    os.chmod(path, mode)
    with pytest.raises(key_files.KeyFileError, match='chmod 600 %s' % path):
        key_files.load_key(path)


@pytest.mark.parametrize('text, message', [
    ('zz' * 32, 'not hex'), ('ab' * 8 + 'a', 'not hex'),
    ('ab' * 15, '15 bytes'), ('ab' * 20, r'20 bytes \(40 hex characters\), not 32'),
    ('ab' * 33, '33 bytes')])
def test_a_key_that_is_not_one_is_refused(tmp_path, text, message):
    path = tmp_path / 'fleet.key'
    path.write_text(text)
    os.chmod(str(path), 0o600)
    with pytest.raises(key_files.KeyFileError, match=message):
        key_files.load_key(str(path))
    with pytest.raises(key_files.KeyFileError, match='cannot read'):
        key_files.load_key(str(tmp_path / 'missing.key'))


def test_each_role_signs_only_what_the_table_gives_it():
    clock = Clock()
    verifier = seal.Verifier([KEY], clock=clock)
    for role in seal.ROLES:
        sealer = seal.Sealer(seal.Keys.from_fleet(b'k' * 32, role), '/node', clock)
        seq = sealer.next_seq()
        mac = sealer.mac(seq, b'flag')
        why = verifier.refusal('/node', seq, mac, b'flag', role='manager')
        if role == 'manager':
            assert why is None
        else:
            assert why == 'signed with the %s key: only the manager role may publish it' % role
    assert seal.publisher_role('server_select/SelectionFlag') == 'manager'
    assert seal.publisher_role('server_select/RobotRanking') == 'robot'   # its own ranking
    assert seal.publisher_role('server_select/LatencyProbeResponse') == 'server'
    assert seal.publisher_role('server_select/LatencySamples') == 'robot'
    assert seal.publisher_role('wordcount/WordCountResult') == 'server'    # a kind's result


def test_a_role_key_file_signs_as_its_role_only_and_checks_every_role(tmp_path):
    fleet = str(tmp_path / 'fleet.key')
    key_files.make_key(fleet)
    robot, observer = str(tmp_path / 'robot.key'), str(tmp_path / 'observer.key')
    assert key_files.make_key_cli(['--role', 'robot', '--fleet', fleet, robot]) == 0
    assert key_files.make_key_cli(['--role', 'observer', '--fleet', fleet, observer]) == 0
    assert stat.S_IMODE(os.stat(robot).st_mode) == 0o600
    derived = key_files.load_keys(fleet, 'manager')      # the fleet key holds every role
    keys = key_files.load_keys(robot, 'robot')
    assert keys.role == 'robot' and keys.private is not None
    clock = Clock()
    verifier = seal.Verifier([derived], clock=clock)
    sealer = seal.Sealer(keys, '/robot1', clock)
    seq = sealer.next_seq()
    assert verifier.refusal('/robot1', seq, sealer.mac(seq, b's'), b's', role='robot') is None
    # the robot's file checks what the manager signs, and cannot make it
    manager = seal.Sealer(derived, '/manager', clock)
    seq = manager.next_seq()
    assert seal.Verifier([keys], clock=clock).refusal(
        '/manager', seq, manager.mac(seq, b'f'), b'f', role='manager') is None
    with pytest.raises(key_files.KeyFileError, match='make_key --role manager'):
        key_files.load_keys(robot, 'manager')
    with pytest.raises(key_files.KeyFileError, match='signs as nobody'):
        key_files.load_keys(observer, 'server')
    watcher = key_files.load_keys(observer)
    assert watcher.private is None and watcher.role is None
    with pytest.raises(ValueError):
        seal.Sealer(watcher, '/top')


def test_a_file_that_is_no_key_is_refused_by_name(tmp_path):
    path = tmp_path / 'junk.key'
    path.write_text('role robot\nsign zz\n')
    os.chmod(str(path), 0o600)
    with pytest.raises(key_files.KeyFileError, match='neither a fleet key nor a role key'):
        key_files.load_keys(str(path), 'robot')
    with pytest.raises(SystemExit, match='1'):
        key_files.make_key_cli(['--role', 'robot', '--fleet', str(path), str(tmp_path / 'o')])


def test_role_keys_come_from_hkdf_sha256_as_rfc_5869_gives_it():
    # RFC 5869, A.1 (with salt) and A.3 (no salt, no info)
    ikm = bytes.fromhex('0b' * 22)
    assert key_files.hkdf_sha256(ikm, bytes.fromhex('f0f1f2f3f4f5f6f7f8f9'), 42, bytes(
        range(13))).hex() == ('3cb25f25faacd57a90434f64d0362f2a2d2d0a90cf1a5a4c5db02d56ecc4c5bf'
                              '34007208d5b887185865')
    assert key_files.hkdf_sha256(ikm, b'', 42).hex() == (
        '8da4e775a563c18f715f802a063c5a31b8a11f5c5ee1879ec3454e5f3c738d2d9d201395faa4b61a96c8')
    assert key_files.role_seed(b'k' * 32, 'robot') != key_files.role_seed(b'k' * 32, 'server')
