"""Construction checks: messages name the parameter (and the mode, for stabilisability/detectability)."""

import numpy as np
import pytest

from netsim.control.design_checks import (
    as_input_matrix,
    as_matrix,
    check_detectable,
    check_poles,
    check_stabilizable,
    check_weight,
    uncontrollable_modes,
)
from netsim.errors import ConfigError


def test_scalars_vectors_and_diagonals():
    assert as_matrix("A", 2.0).shape == (1, 1)
    assert as_input_matrix("B", [0.0, 1.0], 2).shape == (2, 1)
    np.testing.assert_array_equal(check_weight("Q", [1.0, 2.0], 2, definite=True), np.diag([1.0, 2.0]))
    np.testing.assert_array_equal(check_weight("R", 3.0, 2, definite=True), 3.0 * np.eye(2))


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: as_matrix("A", [[1.0, np.nan]]), "A contains NaN"),
        (lambda: as_matrix("A", "abc"), "A must be a numeric matrix"),
        (lambda: as_matrix("A", np.zeros((2, 2, 2))), "A must be a matrix"),
        (lambda: as_matrix("C", np.zeros((1, 3)), (None, 2)), "C must be anyx2, got 1x3"),
        (lambda: check_weight("Q", [1.0, 2.0, 3.0], 2, definite=False), "Q given as a diagonal must have 2 entries"),
        (
            lambda: check_weight("R", np.diag([1.0, 0.0]), 2, definite=True),
            r"R must be positive definite \(smallest eigenvalue 0",
        ),
        (
            lambda: check_weight("Q", [[1.0, 2.0], [2.0, 1.0]], 2, definite=False),
            r"Q must be positive semidefinite \(smallest eigenvalue -1",
        ),
        (lambda: check_poles("poles", [0.5, 1.5], 2), r"1\.5"),
    ],
)
def test_messages_name_the_parameter(call, match):
    with pytest.raises(ConfigError, match=match):
        call()


def test_pbh_finds_exactly_the_hidden_unstable_mode():
    A = np.diag([1.5, 0.3, -1.0])
    B = np.array([[1.0], [0.0], [0.0]])
    # modes 0.3 and -1.0 are not reached; only -1.0 is on/outside the unit circle
    assert uncontrollable_modes(A, B) == [complex(-1.0)]
    assert sorted(m.real for m in uncontrollable_modes(A, B, only_unstable=False)) == [-1.0, 0.3]
    with pytest.raises(ConfigError, match=r"\(A, B\) is not stabilisable: the mode\(s\) at eigenvalue -1 "):
        check_stabilizable(A, B)
    check_detectable(A, np.array([[1.0, 0.0, 1.0]]))  # 0.3 unseen but stable: detectable
    with pytest.raises(ConfigError, match=r"not detectable: the mode\(s\) at eigenvalue 1\.5"):
        check_detectable(A, np.array([[0.0, 1.0, 1.0]]))
