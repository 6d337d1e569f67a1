"""Column names of a run's table (trajectory.csv / trajectory.parquet), each with its unit.

A column name is ``<quantity>_<unit>``: the unit after the last word of the quantity, with
``_`` for a space, ``s2`` for s^2 (``ref_ax_m_s2`` is an acceleration in m/s^2). Angles are in
radians here (the plots show degrees and say so). Defined once; the writers, the readers
(``quadcog animate``) and the docs use these names.
"""
from quadcog.model.conventions import INPUT_NAMES, STATE_NAMES

__all__ = ["STATE_UNITS", "INPUT_UNITS", "REFERENCE", "trajectory_columns", "T", "X", "U", "REF",
           "R_HAT", "R_G", "ROTOR_COMMAND", "ROTOR_THRUST", "MASS"]

# unit of each state entry, in the order of STATE_NAMES
STATE_UNITS = ("m", "m", "m", "rad", "rad", "rad", "m_s", "m_s", "m_s", "rad_s", "rad_s", "rad_s")
INPUT_UNITS = ("N", "N_m", "N_m", "N_m")
# the 14 reference entries (quadcog.trajectories.analytic: p, v, a, j, yaw, yaw rate)
REFERENCE = (("x", "m"), ("y", "m"), ("z", "m"), ("vx", "m_s"), ("vy", "m_s"), ("vz", "m_s"),
             ("ax", "m_s2"), ("ay", "m_s2"), ("az", "m_s2"), ("jx", "m_s3"), ("jy", "m_s3"),
             ("jz", "m_s3"), ("yaw", "rad"), ("yaw_rate", "rad_s"))


def trajectory_columns() -> tuple[str, ...]:
    """The column names of a run's table.

    Returns
    -------
    tuple of str
        In order: time, state (12), input (4), reference (14), r_hat (3), r_G (3), each
        rotor's commanded and delivered thrust (4 + 4), the whole body's mass: 46 names, each
        ``<quantity>_<unit>`` (``t_s``, ``x_m``, ..., ``r_G_z_m``, ..., ``mass_kg``). r_G and
        mass are the truth's, airframe and payloads together.
    """
    return (("t_s",)
            + tuple(f"{n}_{u}" for n, u in zip(STATE_NAMES, STATE_UNITS))
            + tuple(f"{n}_{u}" for n, u in zip(INPUT_NAMES, INPUT_UNITS))
            + tuple(f"ref_{n}_{u}" for n, u in REFERENCE)
            + tuple(f"r_hat_{a}_m" for a in "xyz") + tuple(f"r_G_{a}_m" for a in "xyz")
            + tuple(f"rotor{i}_command_N" for i in range(1, 5))
            + tuple(f"rotor{i}_thrust_N" for i in range(1, 5)) + ("mass_kg",))


# Column slices, so a reader says which block it means.
T, X, U = slice(0, 1), slice(1, 13), slice(13, 17)
REF, R_HAT, R_G = slice(17, 31), slice(31, 34), slice(34, 37)
# per rotor: commanded (the inverse mixer of U) and applied thrust (N); after the 37 columns
# that older run folders have
ROTOR_COMMAND, ROTOR_THRUST = slice(37, 41), slice(41, 45)
MASS = slice(45, 46)        # the whole body's true mass (kg), after the rotor columns
