"""The plant's record_grid sample at t comes after everything of t, actuations by tasks included."""

import numpy as np

from netsim.env import SimEnv
from netsim.kernel import Kernel
from netsim.plant.lti import LTIPlant
from netsim.timebase import MS


def test_grid_sample_sees_the_input_a_task_sets_at_that_instant():
    # A static gain y = D u (D = 1, no state dynamics). A task released every 10 ms writes u = k + 1 in job k
    # at its release; the grid samples y every 10 ms, at the same instants. Each sample, taken after the
    # instant's dispatch, sees the input just written: y(10 k ms) = k + 1 (also at 0, where the first
    # sample used to come before the task's first write and read the initial u = 0).
    env = SimEnv(seed=0)
    plant = LTIPlant(np.zeros((1, 1)), np.zeros((1, 1)), np.zeros((1, 1)), np.ones((1, 1)), output_names=["y"])
    plant.bind(env, record_grid_ns=10 * MS)
    k = Kernel(env, "node", policy="fp")
    k.attach_analog_out("u", lambda t, v: plant.set_input(0, v, t))

    def body(job):
        yield job.analog_out("u", float(job.job_id + 1))
        yield job.execute(1 * MS)

    k.create_task("act", body, period=10 * MS, priority=1)
    env.run(40 * MS)
    assert env.recorder.times["y"] == [0, 10 * MS, 20 * MS, 30 * MS, 40 * MS]
    assert env.recorder.values["y"] == [1.0, 2.0, 3.0, 4.0, 5.0]
