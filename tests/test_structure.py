"""The structure of the equations of motion. The identities of M, C, D, g_G and the truth
model at random points are in report/identities.py (tests/test_identities.py); here, the
runtime's numpy B_U against the derivation."""
import numpy as np

from quadcog.model.conventions import B_U


def test_input_matrix_is_the_derived_one(derived):
    """The runtime's numpy B_U (quadcog.model.conventions) is the B_u of the SymPy derivation."""
    assert np.array(derived.body.B_u, dtype=float).tolist() == B_U.tolist()
