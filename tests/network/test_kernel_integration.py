"""With real kernels: TrueTime's networked control example gives 3.5 ms from sampling to actuation."""

import pytest

from netsim.env import SimEnv
from netsim.kernel import Kernel
from netsim.network import make_network
from netsim.timebase import MS, US


def _networked_loop(net_type, extra=None, seed=0):
    """Sensor -> controller -> actuator over one network (TrueTime's 'networked' example, no interference).

    80 kbit/s and 80-bit frames: 1 ms per frame; each node computes for 0.5 ms.
    """
    env = SimEnv(seed=seed)
    nodes = ["sensor", "controller", "actuator"]
    net = make_network(env, "net", net_type, {"nodes": nodes, "bitrate": "80 kbit/s", "min_frame_bits": 80,
                                              **(extra or {})})
    kernels = {n: Kernel(env, n, policy="fp") for n in nodes}
    for n, k in kernels.items():
        k.attach_network(net)
        net.attach(n, k)
    samples, actuations = [], []
    kernels["sensor"].attach_analog_in("y", lambda t: float(t))
    kernels["actuator"].attach_analog_out("u", lambda t, v: actuations.append((t, v)))

    def sensor(job):
        y = yield job.analog_in("y")
        samples.append(job.now)
        yield job.execute(500 * US)
        yield job.send("net", "controller", y, 80, priority=2)

    def controller(job):
        msg = yield job.receive("net")
        yield job.execute(500 * US)
        yield job.send("net", "actuator", msg.payload, 80, priority=1)

    def actuator(job):
        msg = yield job.receive("net")
        yield job.execute(500 * US)
        yield job.analog_out("u", msg.payload)

    kernels["sensor"].create_task("sample", sensor, period=10 * MS, priority=1)
    kernels["controller"].create_task("control", controller, priority=1)
    kernels["actuator"].create_task("actuate", actuator, priority=1)
    kernels["controller"].bind_receive("net", "control")
    kernels["actuator"].bind_receive("net", "actuate")
    env.run(95 * MS)  # ten periods, the last actuation at 93.5 ms
    return samples, actuations, net


@pytest.mark.parametrize("net_type", ["can", "csma_cd"])
def test_truetime_networked_example_takes_3_5_ms(net_type):
    samples, actuations, net = _networked_loop(net_type)
    # 0.5 ms sensor + 1 ms frame + 0.5 ms controller + 1 ms frame + 0.5 ms actuator = 3.5 ms
    assert len(samples) == 10 and len(actuations) == 10
    for t_sample, (t_act, value) in zip(samples, actuations):
        assert value == float(t_sample)  # the sample that was taken is the one actuated
        assert t_act - t_sample == 3500 * US
    m = net.metrics(95 * MS)
    assert m["utilization"] == pytest.approx(20 * MS / (95 * MS))  # two 1 ms frames per 10 ms period
    assert m["delivered"] == 20 and m["dropped"] == 0


def test_interface_delays_add_to_the_loop_delay():
    samples, actuations, _ = _networked_loop("can", {"pre_delay": "100 us", "post_delay": "50 us"})
    # each of the two hops adds 0.1 ms (sender interface) + 0.05 ms (receiver interface)
    assert {t_act - t_s for t_s, (t_act, _) in zip(samples, actuations)} == {3800 * US}
