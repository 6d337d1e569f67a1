"""Physical consistency of the ten inertial parameters (quadcog.model.inertial_parameters), against oracles
written here: the second moments of point-mass clouds summed particle by particle, the
triangle inequality of the principal inertias about the CoG, the parallel-axis theorem and a
box integrated numerically as a grid of point masses."""
import numpy as np
import pytest

import quadcog
from quadcog.errors import InputError, ParameterError, PhysicalConsistencyError
from quadcog.model.inertial_parameters import (
    PI_NAMES,
    box,
    check_physically_consistent,
    combine,
    from_inertial_parameters,
    inertia_about_cog,
    inertial_arguments,
    inertial_parameters,
    is_physically_consistent,
    parallel_axis,
    point_mass,
    pseudo_inertia,
)

ENTRIES = [(0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2)]      # Ixx, Ixy, Iyy, Ixz, Iyz, Izz


def _cloud(rng, n):
    return rng.uniform(0.01, 1.0, n), rng.normal(0.0, 0.2, (n, 3)) + rng.uniform(-0.1, 0.1, 3)


def _cloud_pi(masses, points):
    """pi of point masses from the definitions: m = sum m_i, h = sum m_i r_i,
    I_O = sum m_i (|r_i|^2 I - r_i r_i^T), entries in PI_NAMES order."""
    I = sum(m * (r @ r * np.eye(3) - np.outer(r, r)) for m, r in zip(masses, points))
    h = sum(m * r for m, r in zip(masses, points))
    return np.array([sum(masses), *h, *(I[i, j] for i, j in ENTRIES)])


def _rotation(rng):
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def _with_principal(rng, principal, m=0.8):
    """pi of a body of mass m with CoG at a random r, principal inertias about the CoG
    ``principal`` along random axes."""
    Rot = _rotation(rng)
    r = rng.uniform(-0.1, 0.1, 3)
    I_G = Rot @ np.diag(principal) @ Rot.T
    I_O = I_G + m * (r @ r * np.eye(3) - np.outer(r, r))     # parallel axis, written here
    return inertial_parameters(m, r, I_O)


def test_names_are_pinocchios_order():
    assert PI_NAMES == ("m", "mx_G", "my_G", "mz_G", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")


def test_pseudo_inertia_is_the_second_moment_of_the_cloud():
    rng = np.random.default_rng(0)
    for _ in range(50):
        masses, points = _cloud(rng, rng.integers(4, 12))
        J = sum(m * np.outer(np.append(r, 1.0), np.append(r, 1.0))
                for m, r in zip(masses, points))
        np.testing.assert_allclose(pseudo_inertia(_cloud_pi(masses, points)), J, rtol=1e-12,
                                   atol=1e-15)


def test_point_mass_clouds_are_consistent():
    rng = np.random.default_rng(1)
    for _ in range(300):
        masses, points = _cloud(rng, rng.integers(4, 20))
        pi = _cloud_pi(masses, points)
        assert is_physically_consistent(pi)
        assert check_physically_consistent(pi).tolist() == pi.tolist()
        np.testing.assert_allclose(combine([point_mass(m, r) for m, r in zip(masses, points)]),
                                   pi, rtol=1e-12, atol=1e-15)


def test_flat_and_single_point_bodies_are_not():
    """Three point masses lie in a plane: J is only semidefinite (no volume)."""
    rng = np.random.default_rng(2)
    masses, points = _cloud(rng, 3)
    assert not is_physically_consistent(_cloud_pi(masses, points))
    assert not is_physically_consistent(point_mass(0.2, [0.1, 0.0, 0.0]))
    with pytest.raises(PhysicalConsistencyError, match="flat|triangle|principal"):
        check_physically_consistent(point_mass(0.2, [0.1, 0.0, 0.0]))


def test_triangle_inequality_decides():
    """I_1, I_2 and I_3 = (I_1 + I_2)(1 + eps): consistent for eps < 0, refused for eps > 0,
    with the message naming the triangle inequality and the three principal inertias."""
    rng = np.random.default_rng(3)
    for _ in range(100):
        a, b = rng.uniform(1e-3, 1e-2, 2)
        for eps, ok in ((-1e-6, True), (-1e-3, True), (1e-6, False), (1e-3, False),
                        (0.5, False)):
            pi = _with_principal(rng, rng.permutation([a, b, (a + b) * (1 + eps)]))
            assert is_physically_consistent(pi) == ok, (a, b, eps)
            if not ok:
                with pytest.raises(PhysicalConsistencyError) as err:
                    check_physically_consistent(pi, "payload")
                text = str(err.value)
                assert text.startswith("payload = [") and "pseudo-inertia" in text
                assert "triangle inequality" in text and f"{a + b:.6g}" in text


def test_perturbed_clouds_that_break_the_triangle_inequality_are_refused():
    """A consistent cloud, its inertia about the CoG pushed along its largest principal axis
    until I_3 exceeds I_1 + I_2: refused."""
    rng = np.random.default_rng(4)
    for _ in range(100):
        masses, points = _cloud(rng, 8)
        pi = _cloud_pi(masses, points)
        m, r, I_O = from_inertial_parameters(pi)
        w, V = np.linalg.eigh(inertia_about_cog(pi))
        extra = (w[0] + w[1] - w[2]) * 1.001             # > 0 for a consistent body
        I_bad = I_O + extra * np.outer(V[:, 2], V[:, 2])
        assert not is_physically_consistent(inertial_parameters(m, r, I_bad))
        with pytest.raises(PhysicalConsistencyError, match="triangle inequality"):
            check_physically_consistent(inertial_parameters(m, r, I_bad))
        # just short of the rim, still a body
        assert is_physically_consistent(inertial_parameters(m, r, I_O + 0.99 * extra / 1.001
                                                            * np.outer(V[:, 2], V[:, 2])))


def test_mass_and_negative_inertia_messages():
    pi = box(1.0, [0.2, 0.2, 0.1], [0.0, 0.0, 0.0])
    for m in (0.0, -0.5):
        bad = pi.copy()
        bad[0] = m
        with pytest.raises(PhysicalConsistencyError, match=r"the mass m = .* kg is not > 0"):
            check_physically_consistent(bad, "pi")
    bad = _with_principal(np.random.default_rng(5), [-1e-3, 5e-3, 5e-3])
    with pytest.raises(PhysicalConsistencyError, match=r"principal inertia -0\.001 kg m\^2 <= 0"):
        check_physically_consistent(bad)
    with pytest.raises(ParameterError, match=r"pi\[4\] \(Ixx\) = nan is not finite"):
        check_physically_consistent(np.where(np.arange(10) == 4, np.nan, pi))
    with pytest.raises(InputError, match=r"expected an array of shape \(10,\)"):
        check_physically_consistent(pi[:9])
    assert issubclass(PhysicalConsistencyError, ParameterError)


def test_combine_is_the_parallel_axis_theorem():
    """Two boxes and a point mass: the combined mass, CoG and inertia about the combined CoG
    by the parallel-axis theorem written here."""
    rng = np.random.default_rng(6)
    for _ in range(50):
        ms = rng.uniform(0.05, 1.0, 3)
        sizes = rng.uniform(0.0, 0.4, (2, 3))
        rs = rng.uniform(-0.2, 0.2, (3, 3))
        own = [m / 12 * np.diag([s[1]**2 + s[2]**2, s[0]**2 + s[2]**2, s[0]**2 + s[1]**2])
               for m, s in zip(ms[:2], sizes)] + [np.zeros((3, 3))]
        pi = combine([box(ms[0], sizes[0], rs[0]), box(ms[1], sizes[1], rs[1]),
                      point_mass(ms[2], rs[2])])
        m, r_G, I_O = from_inertial_parameters(pi)
        r_c = (ms[:, None] * rs).sum(axis=0) / ms.sum()
        shift = lambda mass, d: mass * (d @ d * np.eye(3) - np.outer(d, d))
        np.testing.assert_allclose([m, *r_G], [ms.sum(), *r_c], rtol=1e-12)
        np.testing.assert_allclose(I_O, sum(I + shift(mi, ri) for I, mi, ri in zip(own, ms, rs)),
                                   rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(inertia_about_cog(pi),
                                   sum(I + shift(mi, ri - r_c) for I, mi, ri in zip(own, ms, rs)),
                                   rtol=1e-10, atol=1e-15)
        np.testing.assert_allclose(parallel_axis(own[0], ms[0], rs[0]),
                                   own[0] + shift(ms[0], rs[0]), rtol=1e-12, atol=1e-15)


def test_box_is_a_grid_of_point_masses():
    """A box integrated as n^3 equal point masses at the cell centres: the second moment of
    the grid is the box's less the cells' own, m h^2 / 12 along each axis of cell size h."""
    m, size, centre, n = 0.7, np.array([0.3, 0.1, 0.2]), np.array([0.05, -0.1, 0.02]), 12
    h = size / n
    axes = [centre[k] - size[k] / 2 + h[k] * (np.arange(n) + 0.5) for k in range(3)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    grid = _cloud_pi(np.full(len(points), m / len(points)), points)
    Sigma_cells = m * h**2 / 12                                  # per axis, the cells' own
    I_cells = np.diag([Sigma_cells[1] + Sigma_cells[2], Sigma_cells[0] + Sigma_cells[2],
                       Sigma_cells[0] + Sigma_cells[1]])
    grid[4:] += [I_cells[i, j] for i, j in ENTRIES]
    np.testing.assert_allclose(box(m, size, centre), grid, rtol=1e-12, atol=1e-15)


def test_round_trip_and_bad_arguments():
    rng = np.random.default_rng(8)
    I = rng.normal(size=(3, 3))
    I = I @ I.T
    m, r, I_O = from_inertial_parameters(inertial_parameters(0.5, [0.1, -0.2, 0.3], I))
    assert m == 0.5 and np.allclose(r, [0.1, -0.2, 0.3], rtol=1e-15) and np.allclose(I_O, I)
    with pytest.raises(InputError, match="symmetric"):
        inertial_parameters(0.5, [0, 0, 0], np.triu(I))
    with pytest.raises(InputError, match=r"box: size: expected three edge lengths >= 0"):
        box(1.0, [0.1, -0.1, 0.1], [0, 0, 0])
    with pytest.raises(InputError, match="point_mass: m"):
        point_mass(0.0, [0, 0, 0])
    with pytest.raises(InputError, match="non-empty list"):
        combine([])
    with pytest.raises(InputError, match=r"combine: bodies\[1\]"):
        combine([box(1.0, [0.1] * 3, [0] * 3), np.zeros(9)])


def test_default_vehicle_rim_along_z():
    """The paper's model holds I_O = diag(Ixx, Ixx, Izz): a CoG offset z_G along the axis
    leaves I_G = diag(Ixx - m z^2, Ixx - m z^2, Izz), a body only while
    Izz < 2 (Ixx - m z^2), i.e. z_G < sqrt((2 Ixx - Izz) / (2 m)) (3.83 cm for the
    Hummingbird, inside the 10.09 cm of the admissible ball; 9.39 cm along x or y;
    docs/model.md sec. 7.2)."""
    p = quadcog.default_parameters()
    m, Ixx, Izz = p[0], p[2], p[4]
    rim = np.sqrt((2 * Ixx - Izz) / (2 * m))
    assert round(rim, 4) == 0.0383
    for z, ok in ((0.99 * rim, True), (1.01 * rim, False)):
        # parameter-level with_cog: a Vehicle itself now refuses the inconsistent side
        pi, _, _ = inertial_arguments(quadcog.with_cog(p, [0.0, 0.0, z]))
        assert is_physically_consistent(pi) == ok
    # along x: I_G = diag(Ixx, Iyy - m x^2, Izz - m x^2), Ixx < Iyy + Izz - 2 m x^2
    rim_x = np.sqrt((p[3] + p[4] - p[2]) / (2 * m))
    assert round(rim_x, 4) == 0.0939
    for x_G, ok in ((0.99 * rim_x, True), (1.01 * rim_x, False)):
        for key in ("x_G", "y_G"):
            r = [x_G, 0.0, 0.0] if key == "x_G" else [0.0, x_G, 0.0]
            pi, _, _ = inertial_arguments(quadcog.with_cog(p, r))
            assert is_physically_consistent(pi) == ok
    # a Vehicle checks only the inertia it states (the paper's model holds I_O while the CoG
    # moves, and its scenarios fly beyond this rim): both sides are accepted
    quadcog.default_parameters(z_G=0.99 * rim)
    quadcog.default_parameters(z_G=1.01 * rim)


def test_model_refuses_inconsistent_pi(model):
    x, U = np.zeros(12), np.array([6.0, 0.0, 0.0, 0.0])
    pi, g, c = inertial_arguments(quadcog.default_parameters())
    model.inertial_dynamics(x, U, pi, g, c)
    bad = pi.copy()
    bad[9] = 3 * pi[4]                                         # Izz > Ixx + Iyy
    with pytest.raises(PhysicalConsistencyError, match="triangle inequality"):
        model.inertial_dynamics(x, U, bad, g, c)
    with pytest.raises(PhysicalConsistencyError):
        model.inertial_mass_matrix(bad)
    with pytest.raises(ParameterError, match=r"^g: expected a positive number"):
        model.inertial_dynamics(x, U, pi, 0.0, c)
    with pytest.raises(ParameterError, match=r"^c\[2\]: expected a number >= 0"):
        model.inertial_dynamics(x, U, pi, g, [0, 0, -1, 0, 0, 0])
    with pytest.raises(InputError, match=r"^nu_dot: expected an array of shape \(6,\)"):
        model.inertial_regressor(x, np.zeros(5), g)
