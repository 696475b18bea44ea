"""What a peer may make a node keep or print, bounded (core/util/bounded.py)."""

from server_select.core.util.bounded import PEER_CHARS, PeerCounter, peer


def test_a_long_peer_name_is_cut_to_its_start_and_length():
    assert peer('/robot1') == '/robot1'
    long_name = '/x' * 450000                     # a 900 KB callerid
    cut = peer(long_name)
    assert len(cut) <= PEER_CHARS and cut.startswith('/x/x') and '(900000 chars)' in cut


def test_a_table_by_peer_keeps_the_latest_peers_and_counts_them_all():
    counts = PeerCounter(most=3)
    for n in range(1300):                          # 1,300 made-up names of 900 KB
        counts.add('/intruder%d' % n + 'x' * 900000)
    counts.add('/robot1')
    counts.add('/robot1')
    assert len(counts) == 3 and counts.total == 1302
    assert counts['/robot1'] == 2
    assert all(len(key) <= PEER_CHARS for key in counts)
