"""Process noise set after construction (as the scenario builder does) equals noise given to the constructor."""

import numpy as np

from netsim.env import SimEnv
from netsim.plant import DiscretePlant, LTIPlant
from netsim.timebase import MS


def _trajectory(plant, seed=4):
    plant.bind(SimEnv(seed=seed))
    return np.array([plant.output(k * MS).copy() for k in range(1, 50)])


def test_lti_setter_matches_constructor_noise():
    A, B, C = [[0.0, 1.0], [0.0, -2.0]], [[0.0], [1.0]], [[1.0, 0.0]]
    given = _trajectory(LTIPlant(A, B, C, process_noise=[0.01, 0.04]))
    later = LTIPlant(A, B, C)
    later.set_process_noise([0.01, 0.04])
    np.testing.assert_array_equal(_trajectory(later), given)
    assert np.any(given != 0.0)  # the noise really acts (a noise-free plant at rest stays at 0)


def test_discrete_setter_matches_constructor_noise():
    args = ([[0.9]], [[1.0]], [[1.0]], [[0.0]], MS)
    given = _trajectory(DiscretePlant(*args, process_noise=[0.5]))
    later = DiscretePlant(*args)
    later.set_process_noise([0.5])
    np.testing.assert_array_equal(_trajectory(later), given)
    assert np.any(given != 0.0)
