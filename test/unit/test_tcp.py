import socket
import struct

from server_select.core.util import tcp


def info(unacked, rto_us, backoff):
    """The head of a TCP_INFO as the kernel writes it (the rest zeros)."""
    return struct.pack('=8B5I', 1, 0, backoff, 0, backoff, 0, 0, 0,
                       rto_us, 40000, 1448, 536, unacked) + bytes(100)


def test_parse_reads_unacked_the_backed_off_timeout_and_the_backoff():
    state = tcp.parse(info(unacked=3, rto_us=6400000, backoff=5))
    assert state == tcp.Retransmission(unacked=3, rto=6.4, backoff=5)
    assert tcp.parse(b'\0' * 10) is None


def test_a_connection_through_an_outage_is_stalled_one_lost_packet_is_not(monkeypatch):
    seen = {}
    monkeypatch.setattr(tcp, 'retransmission', lambda sock: seen[sock])
    seen.update(outage=tcp.parse(info(2, 3200000, 4)),   # 0.2 s doubled 4 times
                lost_one=tcp.parse(info(1, 408000, 1)),  # one retransmission
                idle=tcp.parse(info(0, 3200000, 0)),     # backed off, nothing in flight
                unknown=None)
    assert [tcp.stalled(s) for s in ('outage', 'lost_one', 'idle', 'unknown')] == \
        [True, False, False, False]


def test_a_live_loopback_connection_reads_and_is_not_stalled():
    server = socket.socket()
    server.bind(('127.0.0.1', 0))
    server.listen(1)
    client = socket.create_connection(server.getsockname())
    peer, _ = server.accept()
    try:
        client.sendall(b'x' * 1000)
        assert peer.recv(1000)
        state = tcp.retransmission(client)
        assert state is not None and 0.0 < state.rto < tcp.STALLED_RTO
        assert not tcp.stalled(client)
        assert tcp.retransmission(socket.socket(socket.AF_INET, socket.SOCK_DGRAM)) is None
        assert tcp.retransmission(None) is None
    finally:
        for sock in (client, peer, server):
            sock.close()
