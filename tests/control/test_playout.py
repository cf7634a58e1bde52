"""Control packets with future actions and the actuator playout buffer."""

from netsim.control import ControlPacket, PlayoutBuffer


def test_playout_applies_current_then_future_then_holds_last():
    buf = PlayoutBuffer(u0=-1.0)
    assert buf.value(0) == -1.0  # before any packet: initial value
    buf.receive(ControlPacket.of(10, [1.0, 2.0, 3.0]))
    assert [buf.value(j) for j in range(10, 15)] == [1.0, 2.0, 3.0, 3.0, 3.0]
    assert buf.exhausted(13) and not buf.exhausted(12)


def test_newer_packet_replaces_and_stale_packet_is_discarded():
    buf = PlayoutBuffer()
    buf.receive(ControlPacket.of(10, [1.0, 2.0, 3.0]))
    assert buf.receive(ControlPacket.of(12, [7.0, 8.0]))
    assert not buf.receive(ControlPacket.of(11, [9.0, 9.0]))  # out-of-order arrival
    assert [buf.value(j) for j in (12, 13, 14)] == [7.0, 8.0, 8.0]
    assert buf.stale_count == 1


def test_late_packet_starts_at_the_entry_for_now():
    buf = PlayoutBuffer()
    buf.receive(ControlPacket.of(20, [1.0, 2.0, 3.0]))
    assert buf.value(21) == 2.0  # arrived during period 21: the stale current action is skipped


def test_packet_bits_count_one_word_per_value():
    assert ControlPacket.of(0, [0.0] * 5).bits(32, 64) == 64 + 5 * 32
