"""``matvec``: the plants' per-event matrix-vector product is ``@`` bit for bit."""

from __future__ import annotations

import numpy as np

from netsim.plant import matvec


def test_matvec_matches_the_matmul_operator_bit_for_bit_including_signed_zeros():
    # values chosen to provoke signed zeros, underflow and large magnitudes; both memory layouts
    rng = np.random.default_rng(0)
    values = [0.0, -0.0, 1.0, -1.0, 2.5, -3e-300, 1e-300, 1e300, 0.1, -7.3]
    for rows in range(0, 12):
        for cols in range(0, 12):
            for trial in range(4):
                M = rng.choice(values, size=(rows, cols))
                if trial % 2:
                    M = np.asfortranarray(M)
                v = rng.choice(values, size=cols)
                with np.errstate(all="ignore"):
                    assert matvec(M)(v).tobytes() == (M @ v).tobytes(), (rows, cols, M, v)


def test_one_entry_vectors_where_dot_multiplies_by_a_scalar_give_the_operators_zero():
    # numpy 2's ndarray.dot returns 0.0 * -1.0 = -0.0 here (a scalar product) while `@` returns +0.0 (a sum
    # starting from zero); the plant's output must not depend on which one is used
    M, v = np.array([[0.0]]), np.array([-1.0])
    assert not np.signbit((M @ v)[0])
    assert matvec(M)(v).tobytes() == (M @ v).tobytes()
    C = np.array([[0.0], [1.0], [-0.0]])  # a one-column B or D matrix
    assert matvec(C)(v).tobytes() == (C @ v).tobytes()
