"""`make mutations`: would the tests catch wrong physics? Each mutation is one deliberate
mistake, applied as a small textual edit to a copy of the repository; the tests run in that
copy and must fail.

    python bench/mutations.py                     # every mutation, default test files
    python bench/mutations.py --only gravity_sign # one (repeat --only for several)
    python bench/mutations.py --tests tests/test_physics.py tests/test_vehicle.py
    python bench/mutations.py --list              # the mutations and their edits

For each mutation the script copies the tracked files and the new ones git does not ignore
(``git ls-files --cached --others --exclude-standard``, as they are in the working tree: a new
module or test file not yet added is part of it) into a temporary folder, applies the edit (it
must match exactly once, or the script stops: a moved source must not silently test nothing),
regenerates ``generated/`` with ``python -m derive`` when the edit is in ``derive/`` (and
checks that the generated C changed, so the mistake reaches the compiled model as a real one
would), and runs pytest there with this interpreter, cwd and PYTHONPATH set to the copy (and
QUADCOG_VENDOR_DIR to the checkout's shared/vendor, so that the tests that need the firmware
or PX4 tarballs do not skip). A small pytest plugin checks, inside that pytest process, that
``quadcog``, ``derive``, ``report`` and the generated folder are the copy's (an editable
install points at the checkout). The unmutated copy runs first as a control: every selected
test must pass there, else the script aborts.

When ``python -m derive`` itself refuses a mutated derivation (its own symbolic self-checks,
e.g. that the hover trim U* gives x_dot = 0), the mistake never reaches generated/: that
counts as caught, by derive. A ``*_past_derive`` variant of the same mistake then switches that
one self-check off (a second edit, also asserted), so that the tests show whether they would
catch it on their own. A mutation under which pytest stops before its collection finishes
(``import quadcog`` raises in the copy, e.g. a preset vehicle refuses its own mixer) also counts
as caught, its error named: after a control that collected, no test can run with it.

Prints a table (mutation | where | tests that fail | count) and writes it, with the full list of
failing tests, to out/mutations/results.md. Exit status: 0 when every mutation is caught, 1
when one survives (no test fails and derive accepts it), 2 when the control fails or an edit does not apply.
The user's checkout is never written to except out/mutations/.
"""
import argparse
from dataclasses import dataclass
import json
import os
from pathlib import Path
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

ROOT = Path(__file__).resolve().parent.parent

# Fast test files relevant to physics and the layers beyond it (about 35 s together on a free
# core, compiled code cached: the control run; the 40 mutations take about 20 min in all).
DEFAULT_TESTS = [
    "tests/test_physics.py", "tests/test_vehicle.py", "tests/test_identities.py",
    "tests/test_independent_mechanics.py", "tests/test_hover.py", "tests/test_kinematics.py",
    "tests/test_regressor.py", "tests/test_lie.py", "tests/test_bad_input.py",
    "tests/test_simulate.py", "tests/test_controllers.py", "tests/test_inertial_pinocchio.py",
    "tests/test_inertial_model.py", "tests/test_inertial_consistency.py",
    # the newer layers: log readers, identification, payloads, the payload law (issue 33)
    "tests/test_harden_identify.py",
    # the guards of the layers beyond the model (a second oracle each: Lee's law, Newton, a t
    # table, hand counts, ...): the laws, the timeline and divergence, vehicle files, sweep and
    # identification statistics, the Crazyflie loop's noise; the inline trig and PX4's frames
    "tests/test_guard_controllers.py", "tests/test_guard_timeline.py",
    "tests/test_guard_vehicle_files.py", "tests/test_guard_sweeps.py",
    "tests/test_guard_identification.py", "tests/test_guard_crazyflie.py",
    "tests/test_trig_c.py", "tests/test_px4_frames.py",
]


@dataclass(frozen=True)
class Mutation:
    name: str
    path: str          # file of the edit, relative to the repository
    old: str           # text that must occur exactly once in that file
    new: str           # its replacement
    what: str          # the mistake, in words
    # further edits (path, old, new), each also applied exactly once: used to switch off one of
    # derive's own self-checks, so that a mistake those checks refuse still reaches generated/
    # and the tests show whether they would catch it on their own
    bypass: tuple = ()

    @property
    def derived(self):
        """True when the edit is in the derivation: generated/ is rewritten in the copy."""
        return self.path.startswith("derive/")


MUTATIONS = [
    Mutation("products_of_inertia", "quadcog/sim/plant.py",
             "diag, products = diag + S_diag * m, -m * S_off",
             "diag, products = diag + S_diag * m, m * S_off",
             "sign of the products of inertia of the truth model's parallel-axis I_O"),
    Mutation("products_of_inertia_derive", "derive/symbols.py",
             "I_O_full = sp.Matrix([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])",
             "I_O_full = sp.Matrix([[Ixx, -Ixy, -Ixz], [-Ixy, Iyy, -Iyz], [-Ixz, -Iyz, Izz]])",
             "sign of the products of inertia in the derived truth model and the model in pi "
             "(tensor vs. product convention)"),
    Mutation("products_of_inertia_admissibility", "quadcog/model/parameters.py",
             "- p[IDX[\"m\"]] * (r @ r * np.eye(3) - np.outer(r, r)))",
             "- p[IDX[\"m\"]] * (r @ r * np.eye(3) + np.outer(r, r)))",
             "sign of the products r r^T in the admissibility check's I_G"),
    Mutation("pseudo_inertia_trace", "quadcog/model/inertial_parameters.py",
             "J[:3, :3] = 0.5 * np.trace(I) * np.eye(3) - I",
             "J[:3, :3] = np.trace(I) * np.eye(3) - I",
             "the pseudo-inertia built with tr(I_O) instead of tr(I_O) / 2 (I_O in place of "
             "the second moment Sigma)"),
    Mutation("mixer_yaw_sign", "quadcog/vehicles/vehicle.py",
             "self.moment_constant * np.asarray(self.rotor_directions, float)])",
             "-self.moment_constant * np.asarray(self.rotor_directions, float)])",
             "sign of the yaw row of the mixer (rotor drag moments)"),
    Mutation("rotors_2_4_swapped", "quadcog/vehicles/vehicle.py",
             "pos = np.asarray(self.rotor_positions, dtype=float)\n"
             "        return np.vstack([np.ones(N_ROTORS), pos[:, 1], -pos[:, 0],",
             "pos = np.asarray(self.rotor_positions, dtype=float)[[0, 3, 2, 1]]\n"
             "        return np.vstack([np.ones(N_ROTORS), pos[:, 1], -pos[:, 0],",
             "rotors 2 and 4 swapped in the mixer (positions exchanged, directions kept)"),
    Mutation("rotors_2_4_swapped_layout", "quadcog/vehicles/vehicle.py",
             "return ((a, 0.0), (0.0, a), (-a, 0.0), (0.0, -a))",
             "return ((a, 0.0), (0.0, -a), (-a, 0.0), (0.0, a))",
             "rotors 2 and 4 swapped in the \"+\" layout"),
    Mutation("parallel_axis_dropped", "quadcog/sim/plant.py",
             "diag, products = diag + S_diag * m, -m * S_off",
             "diag, products = diag, -m * S_off",
             "parallel-axis term m (|r|^2 - r_i^2) dropped from the truth model's diagonal I_O"),
    Mutation("parallel_axis_dropped_admissibility", "quadcog/model/parameters.py",
             "return (np.diag(p[IDX[\"Ixx\"]:IDX[\"Izz\"] + 1])\n"
             "                    - p[IDX[\"m\"]] * (r @ r * np.eye(3) - np.outer(r, r)))",
             "return (np.diag(p[IDX[\"Ixx\"]:IDX[\"Izz\"] + 1])\n"
             "                    - 0.0 * (r @ r * np.eye(3) - np.outer(r, r)))",
             "parallel-axis term dropped from I_G in the admissibility check"),
    Mutation("jerk_feed_forward_dropped", "quadcog/controllers/feedback_linearization.py",
             "a_cmd_dot = ref[JERK] + drag * ref[ACC]",
             "a_cmd_dot = drag * ref[ACC]",
             "reference jerk dropped from the rate of the commanded attitude (FL, adaptive FL)"),
    Mutation("gravity_sign", "derive/newton_euler.py",
             "f_G = R.T * sp.Matrix([0, 0, -m * g])",
             "f_G = R.T * sp.Matrix([0, 0, m * g])",
             "sign of gravity in the derivation (weight up); derive's trim self-check refuses "
             "it, generated/ is left as it was"),
    Mutation("gravity_sign_past_derive", "derive/newton_euler.py",
             "f_G = R.T * sp.Matrix([0, 0, -m * g])",
             "f_G = R.T * sp.Matrix([0, 0, m * g])",
             "gravity_sign with derive's trim self-check switched off: the weight points up in "
             "dynamics and truth_dynamics",
             bypass=(("derive/latex.py", 'raise AssertionError("U* is not a trim")',
                      "pass"),)),
    Mutation("gravity_sign_controller", "quadcog/controllers/shaping.py",
             "lift = g + a[2]",
             "lift = -g + a[2]",
             "sign of gravity in the controllers' thrust direction (a_cmd + g e_z)"),
    Mutation("drag_sign", "derive/newton_euler.py",
             "D = sp.diag(c_x, c_y, c_z, c_phi, c_theta, c_psi)",
             "D = -sp.diag(c_x, c_y, c_z, c_phi, c_theta, c_psi)",
             "sign of the drag matrix D in the derivation (drag pushes along the velocity)"),
    Mutation("drag_sign_eom", "derive/vector_field.py",
             "n = body.C * nu + body.D * nu + body.g_G",
             "n = body.C * nu - body.D * nu + body.g_G",
             "sign of D nu in the equations of motion only (D itself exported as diag(c)); "
             "derive's linearization self-check refuses it"),
    Mutation("drag_sign_eom_past_derive", "derive/vector_field.py",
             "n = body.C * nu + body.D * nu + body.g_G",
             "n = body.C * nu - body.D * nu + body.g_G",
             "drag_sign_eom with derive's linearization self-check switched off: drag pushes "
             "along the velocity in dynamics and truth_dynamics",
             bypass=(("derive/latex.py", 'raise AssertionError("linearization at the trim is '
                      'not -M^{-1}[dg_G/deta, D]")', "pass"),)),
    # -- the newer layers (issue 33): log readers, identification, payloads, the payload law
    Mutation("crazyflie_gyro_deg_as_rad", "quadcog/logs/crazyflie.py",
             "s[\"body_rates\"] = np.column_stack([raw[n] for n in names]) * _DEG",
             "s[\"body_rates\"] = np.column_stack([raw[n] for n in names])",
             "the Crazyflie reader takes gyro.x/y/z (deg/s) as rad/s"),
    Mutation("crazyflie_vbat_as_mv", "quadcog/logs/crazyflie.py",
             "s[\"battery_voltage\"] = raw[\"pm.vbat\"].copy()",
             "s[\"battery_voltage\"] = raw[\"pm.vbat\"] * 1e-3",
             "the Crazyflie reader takes pm.vbat (V) as millivolts"),
    Mutation("mass_change_sign", "quadcog/identification/core.py",
             "mass_change, samples = m - mb, samples + sb",
             "mass_change, samples = mb - m, samples + sb",
             "identify's mass_change with its sign flipped (baseline minus flights)"),
    Mutation("payload_project_short_of_the_cone", "quadcog/controllers/payload_adaptive.py",
             "r = ca.if_else(q > keep, r * ca.sqrt(keep / ca.fmax(q, 1e-300)), r)",
             "r = ca.if_else(q > keep, r * ca.sqrt(ca.sqrt(keep / ca.fmax(q, 1e-300))), r)",
             "payload_adaptive's compiled project() scales r_hat only part of the way, "
             "leaving it outside the consistency cone"),
    Mutation("identify_gravity_check_off", "quadcog/identification/plausibility.py",
             "if abs(mean_a) > GRAVITY_FRACTION * g:",
             "if abs(mean_a) > 10 * GRAVITY_FRACTION * g:",
             "identification accepts a vertical acceleration that counts gravity (+-g)"),
    Mutation("identify_time_unit_check_off", "quadcog/identification/plausibility.py",
             "if not RATE_HZ[0] <= 1.0 / step <= RATE_HZ[1] or span > MAX_SPAN:",
             "if not 0.05 <= 1.0 / step <= RATE_HZ[1]:",
             "identification accepts a time column in milliseconds (0.1 Hz)"),
    Mutation("identify_rates_against_angles_off", "quadcog/identification/plausibility.py",
             "        if miss.size and miss.max() > AGREE_TOLERANCE:",
             "        if miss.size and miss.max() > 100 * AGREE_TOLERANCE:",
             "identification accepts body rates in deg/s that turn 57 times further than the "
             "logged angles"),
    Mutation("payload_after_end_silent", "quadcog/sim/prepare.py",
             "if duration is not None and e.t > duration:",
             "if duration is not None and e.t > 10 * duration:",
             "a payload event after the end of the run is accepted silently"),
    # -- the control laws, the compiled kernels' trig, the run's timeline, divergence, vehicle
    # files, PX4 and Crazyflie boundaries, sweep and identification statistics
    Mutation("geometric_rate_cross_term_dropped", "quadcog/controllers/geometric.py",
             "        w_dot = (-self.k_R * e_R - self.k_W * (w - w_c) - ca.cross(w, w_c)\n",
             "        w_dot = (-self.k_R * e_R - self.k_W * (w - w_c)\n",
             "the geometric law's angular acceleration without the -w x (R^T R_c Omega_c) term "
             "(Lee's feed-forward of the rotating desired frame)"),
    Mutation("geometric_attitude_error_order", "quadcog/controllers/geometric.py",
             "e_R = _vee(Rc.T @ R - R.T @ Rc) / 2",
             "e_R = _vee(R.T @ Rc - Rc.T @ R) / 2",
             "the geometric law's e_R = (R_c^T R - R^T R_c)^vee / 2 with the products in the "
             "wrong order (its sign flipped)"),
    Mutation("cascade_yaw_error_unwrapped", "quadcog/controllers/cascade_pd.py",
             "U4 = -kpsi[0] * wrap_angle(x[5] - ref[YAW])",
             "U4 = -kpsi[0] * (x[5] - ref[YAW])",
             "the cascade PD law's yaw error not wrapped to (-pi, pi]: across +-pi it turns "
             "the long way round"),
    Mutation("composite_covariance_unbounded", "quadcog/controllers/composite.py",
             "P_dot = (self.forgetting * P @ (ca.DM.eye(3) - P / k0)",
             "P_dot = (self.forgetting * P",
             "the composite law's forgetting without its bound: P_dot = beta P - ..., the "
             "covariance grows without bound where the data do not excite (z_G at hover)"),
    Mutation("fl_integral_integrates_wrong_rows", "quadcog/controllers/fl_integral.py",
             "return decoupled_input(alpha, v - b), e[ATTITUDE_ROWS]",
             "return decoupled_input(alpha, v - b), e[0:3]",
             "feedback linearization with integral action integrates the z, phi, theta errors "
             "(rows 0-2 of y) instead of phi, theta, psi"),
    Mutation("inline_sine_coefficient_typo", "quadcog/codegen/trig_c.py",
             '"-1.98412698298579493134e-04"',
             '"-1.98412698928579493134e-04"',
             "two digits transposed in the third coefficient of the inline sine's polynomial "
             "(fdlibm's S3)"),
    Mutation("cog_change_one_step_late", "quadcog/sim/timeline.py",
             'starts = np.searchsorted(t, [c.t for c in self.changes], side="left")',
             'starts = np.searchsorted(t, [c.t for c in self.changes], side="right")',
             "a CoG change applies from the first sample after its time, not at it (one step "
             "late: searchsorted's side, on a run's grid of times in order)"),
    Mutation("disturbance_one_step_long", "quadcog/sim/timeline.py",
             'stop = np.searchsorted(t, [d.t + d.duration for d in pulses], side="left")',
             'stop = np.searchsorted(t, [d.t + d.duration for d in pulses], side="right")',
             "a disturbance pulse also acts at the sample of its end time (one step too long: "
             "impulse F (duration + dt); searchsorted's side, on a run's grid)"),
    Mutation("tail_start_is_the_fraction", "quadcog/sim/schedule.py",
             'return (1 - config.get("metrics.tail_fraction")) *',
             'return config.get("metrics.tail_fraction") *',
             "the compiled runs' tail metrics start at tail_fraction * duration (the last 75 % "
             "instead of the last 25 %)"),
    Mutation("divergence_tilt_reads_yaw", "quadcog/sim/divergence.py",
             "tilt = ca.fmax(ca.fabs(x[3]), ca.fabs(x[4]))",
             "tilt = ca.fmax(ca.fabs(x[3]), ca.fabs(x[5]))",
             "the divergence rule's tilt reads yaw (x[5]) in place of pitch (x[4])"),
    Mutation("vehicle_file_inertia_not_moved_to_O", "quadcog/vehicles/description.py",
             "I_O = I_G + m * (float(r_G @ r_G) * np.eye(3) - np.outer(r_G, r_G))",
             "I_O = I_G",
             "a URDF/SDF vehicle's inertia taken about its CoG as I_O (no parallel-axis shift "
             "to O on the rotors' axis)"),
    Mutation("vehicle_file_inertia_rotated_backwards", "quadcog/vehicles/description.py",
             "I_model = where.R @ I_G @ where.R.T",
             "I_model = where.R.T @ I_G @ where.R",
             "a link's inertia turned to model axes with R^T I R instead of R I R^T"),
    Mutation("sweep_quantile_as_percentile", "quadcog/sweeps/summary.py",
             "float(np.quantile(tail, p))",
             "float(np.percentile(tail, p))",
             "the sweep summary's tail RMS quantiles by np.percentile with fractions "
             "(p50 is the 0.5th percentile)"),
    Mutation("ci95_degrees_of_freedom", "quadcog/identification/segments.py",
             "t_quantile(n - 1) * b.std(axis=0, ddof=1)",
             "t_quantile(n) * b.std(axis=0, ddof=1)",
             "the 95 % interval of a mean of n block means with Student's t of n degrees of "
             "freedom instead of n - 1"),
    Mutation("px4_gps_course_swapped", "quadcog/px4/sensors.py",
             "math.atan2(ve, vn)",
             "math.atan2(vn, ve)",
             "HIL_GPS course over ground measured from east (atan2(vn, ve)) instead of north"),
    Mutation("crazyflie_noise_columns_unordered", "quadcog/crazyflie/loop.py",
             "    sig = np.concatenate([sig[0:3], sig[6:9], sig[3:6], sig[9:12]])\n",
             "",
             "the Crazyflie loop's noise in the state's order (attitude's sigma on the world "
             "velocity, velocity's on the Euler angles)"),
]

PROBE = '''"""Loaded by bench/mutations.py with -p: records which quadcog, derive and report this
pytest process imports, and stops the session when they are not the copy's."""
import json
import os
from pathlib import Path

import pytest


def pytest_collection_finish(session):
    import derive, quadcog, quadcog.paths, report
    root = Path(os.environ["QUADCOG_MUTATION_COPY"]).resolve()
    found = {"quadcog": quadcog.__file__, "derive": derive.__file__, "report": report.__file__,
             "generated": str(quadcog.paths.generated_dir())}
    Path(os.environ["QUADCOG_MUTATION_PROBE"]).write_text(json.dumps(found))
    bad = {k: v for k, v in found.items() if not Path(v).resolve().is_relative_to(root)}
    if bad:
        pytest.exit(f"not the copy's modules: {bad}", returncode=3)
'''


class Abort(Exception):
    """The check cannot be trusted (an edit did not apply, the control failed, ...)."""


class NoTestRan(Exception):
    """pytest stopped before its collection finished (e.g. ``import quadcog`` raises in the
    copy): under a mutation, after a control that collected, the mistake stops every test."""


def tracked_files(root):
    """The files git tracks and the new ones it does not ignore (a module or test file not yet
    added is part of the working tree the tests run on)."""
    out = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                         cwd=root, check=True, capture_output=True)
    return list(dict.fromkeys(f for f in out.stdout.decode().split("\0") if f))


def make_pristine(dest):
    """The tracked and new (not ignored) files of the checkout, as they are in its working
    tree, copied to dest."""
    for rel in tracked_files(ROOT):
        src = ROOT / rel
        if not src.is_file():              # deleted in the working tree
            continue
        (dest / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, dest / rel)
    (dest / "_mutation_probe.py").write_text(PROBE)


def edit(name, copy, path, old, new):
    """Replace ``old`` by ``new`` in copy/path; returns 'path:line'. Aborts unless ``old``
    occurs exactly once."""
    f = copy / path
    if not f.is_file():
        raise Abort(f"{name}: {path} does not exist")
    text = f.read_text()
    n = text.count(old)
    if n != 1:
        raise Abort(f"{name}: the text to edit occurs {n} times in {path} "
                    f"(expected exactly once; did the source move?):\n{old}")
    line = text[:text.index(old)].count("\n") + 1
    f.write_text(text.replace(old, new))
    return f"{path}:{line}"


def apply(mutation, copy):
    """Apply the mutation's edit (and its bypass edits) in ``copy``; returns where."""
    where = edit(mutation.name, copy, mutation.path, mutation.old, mutation.new)
    for path, old, new in mutation.bypass:
        where += f" (check off: {edit(mutation.name, copy, path, old, new)})"
    return where


def environment(copy, cache):
    env = dict(os.environ)
    env.pop("QUADCOG_GENERATED", None)            # the copy's generated/, nothing else
    env["PYTHONPATH"] = str(copy) + (os.pathsep + env["PYTHONPATH"]
                                     if env.get("PYTHONPATH") else "")
    env["QUADCOG_CACHE_DIR"] = str(cache)
    # the vendor tarballs (firmware, PX4) are found beside the checkout (shared/vendor); the
    # copy is elsewhere, so without this the tests that need them skip in every copy
    vendor = ROOT.parent / "shared" / "vendor"
    if "QUADCOG_VENDOR_DIR" not in env and vendor.is_dir():
        env["QUADCOG_VENDOR_DIR"] = str(vendor)
    env["QUADCOG_MUTATION_COPY"] = str(copy)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def regenerate(mutation, copy, env, pristine):
    """python -m derive in the copy; None, or the derivation's error when it refuses."""
    res = subprocess.run([sys.executable, "-m", "derive", "--quiet"], cwd=copy, env=env,
                         capture_output=True, text=True, timeout=900)
    if res.returncode != 0:
        last = (res.stderr.strip().splitlines() or ["?"])[-1]
        return f"python -m derive refuses it ({last[:160]})"
    c = "generated/c/quadcog_gen.c"
    if (copy / c).read_bytes() == (pristine / c).read_bytes():
        raise Abort(f"{mutation.name}: {c} did not change after python -m derive; the "
                    "mutation would not reach the compiled model")
    return None


def run_tests(copy, env, tests, workdir, label):
    """pytest in the copy; (failed test ids, exit code, seconds)."""
    xml, probe = workdir / f"{label}.xml", workdir / f"{label}.probe.json"
    for f in (xml, probe):
        f.unlink(missing_ok=True)
    env = dict(env, QUADCOG_MUTATION_PROBE=str(probe))
    cmd = [sys.executable, "-m", "pytest", "-q", "-rfE", "-p", "no:cacheprovider",
           "-p", "_mutation_probe", "-o", "junit_family=xunit1", f"--junitxml={xml}", *tests]
    t0 = time.perf_counter()
    res = subprocess.run(cmd, cwd=copy, env=env, capture_output=True, text=True, timeout=1800)
    seconds = time.perf_counter() - t0
    (workdir / f"{label}.log").write_text(res.stdout + res.stderr)
    if not probe.is_file():
        errors = [line[1:].strip() for line in (res.stdout + res.stderr).splitlines()
                  if line.startswith("E ")]
        raise NoTestRan(f"pytest exited {res.returncode} before collection finished ("
                        f"{(errors or ['?'])[-1][:160]}); see {workdir / (label + '.log')}",
                        (res.stdout + res.stderr)[-2000:])
    found = json.loads(probe.read_text())
    root = copy.resolve()
    bad = {k: v for k, v in found.items() if not Path(v).resolve().is_relative_to(root)}
    if bad or res.returncode == 3:
        raise Abort(f"{label}: pytest imported modules outside the copy {copy}: {bad or found}")
    if res.returncode not in (0, 1) or not xml.is_file():
        raise Abort(f"{label}: pytest exited {res.returncode}; see {workdir / (label + '.log')}")
    failed = []
    for case in ET.parse(xml).getroot().iter("testcase"):
        if case.find("failure") is not None or case.find("error") is not None:
            failed.append(f"{case.get('file') or case.get('classname')}::{case.get('name')}")
    if res.returncode == 1 and not failed:
        raise Abort(f"{label}: pytest exited 1 but the report names no failing test")
    return failed, res.returncode, seconds


def short(test_id):
    return test_id.removeprefix("tests/")


def table(rows, limit=None):
    lines = ["| mutation | where | tests that fail | count |", "|---|---|---|---|"]
    for name, where, failed, refused, _ in rows:
        shown = [short(t) for t in failed]
        if limit and len(shown) > limit:
            shown = shown[:limit] + [f"... (+{len(shown) - limit} more)"]
        cell = "<br>".join(s.replace("|", "\\|") for s in shown) or (
            f"none run: {refused}" if refused else "**none: survives**")
        lines.append(f"| {name} | {where} | {cell} | {len(failed)} |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tests", nargs="+", default=DEFAULT_TESTS,
                    help="test files (or node ids) to run in each copy; default: %(default)s")
    ap.add_argument("--only", action="append", metavar="NAME",
                    help="run only this mutation (repeatable)")
    ap.add_argument("--list", action="store_true", help="list the mutations and exit")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "mutations")
    ap.add_argument("--cache-dir", type=Path, default=None,
                    help="QUADCOG_CACHE_DIR of the copies (compiled code, keyed by source hash); "
                         "default: OUT/cache, kept between runs")
    ap.add_argument("--keep", action="store_true", help="keep the temporary copies")
    args = ap.parse_args(argv)

    if args.list:
        for m in MUTATIONS:
            print(f"{m.name}  ({m.path}{', regenerates generated/' if m.derived else ''})\n"
                  f"    {m.what}\n    - {m.old!r}\n    + {m.new!r}")
            for path, old, new in m.bypass:
                print(f"    and in {path}:\n    - {old!r}\n    + {new!r}")
        return 0
    names = {m.name for m in MUTATIONS}
    unknown = sorted(set(args.only or ()) - names)
    if unknown:
        ap.error(f"unknown mutation(s) {unknown}; expected some of {sorted(names)}")
    selected = [m for m in MUTATIONS if not args.only or m.name in args.only]
    for t in args.tests:
        if not (ROOT / t.split("::")[0]).exists():
            ap.error(f"no such test file: {t}")

    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    cache = (args.cache_dir or out / "cache").resolve()
    cache.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix="quadcog-mutations-"))
    t_start = time.perf_counter()
    rows, timings = [], {}
    try:
        pristine = tmp / "pristine"
        make_pristine(pristine)
        logs = tmp / "logs"
        logs.mkdir()
        print(f"copies in {tmp}; tests: {' '.join(args.tests)}", flush=True)

        control = tmp / "control"
        shutil.copytree(pristine, control)
        try:
            failed, _, seconds = run_tests(control, environment(control, cache), args.tests,
                                           logs, "control")
        except NoTestRan as e:
            raise Abort(f"control: {e.args[0]}\n{e.args[1]}") from None
        timings["control"] = seconds
        print(f"control (no mutation): {len(failed)} failing, {seconds:.0f} s", flush=True)
        if failed:
            raise Abort("the control (no mutation) fails, so a failure under a mutation would "
                        "mean nothing:\n  " + "\n  ".join(failed))
        shutil.rmtree(control)

        for m in selected:
            t0 = time.perf_counter()
            copy = tmp / m.name
            shutil.copytree(pristine, copy)
            where = apply(m, copy)
            env = environment(copy, cache)
            refused = regenerate(m, copy, env, pristine) if m.derived else None
            failed = []
            if not refused:
                try:
                    failed = run_tests(copy, env, args.tests, logs, m.name)[0]
                except NoTestRan as e:       # caught: no test can run with the mistake
                    refused = e.args[0]
            timings[m.name] = time.perf_counter() - t0
            rows.append((m.name, where, failed, refused, m.what))
            print(f"{m.name}: {refused or f'{len(failed)} failing'} ({where}), "
                  f"{timings[m.name]:.0f} s", flush=True)
            if not args.keep:
                shutil.rmtree(copy)
    except Abort as e:
        print(f"mutations: abort: {e}", file=sys.stderr)
        return 2
    finally:
        if args.keep:
            print(f"copies kept in {tmp}")
        else:
            if (tmp / "logs").is_dir():       # pytest output and junit xml of this run
                shutil.rmtree(out / "logs", ignore_errors=True)
                shutil.copytree(tmp / "logs", out / "logs")
            shutil.rmtree(tmp, ignore_errors=True)

    total = time.perf_counter() - t_start
    survivors = [name for name, _, failed, refused, _ in rows if not failed and not refused]
    printed = table(rows, limit=4)
    print()
    print(printed)
    print(f"\n{len(rows)} mutations, {len(rows) - len(survivors)} caught; total {total:.0f} s "
          f"(control {timings['control']:.0f} s)")
    details = ["", "## Failing tests per mutation", ""]
    for name, where, failed, refused, what in rows:
        details += [f"### {name}", "", f"{what} ({where}, {timings[name]:.0f} s)", ""]
        details += [f"- `{t}`" for t in failed] or [
            f"- no test run: {refused}" if refused else "- none: the mutation survives"]
        details.append("")
    (out / "results.md").write_text(
        "# Mutation check (bench/mutations.py)\n\n"
        f"Tests: {' '.join(args.tests)}\n\n" + table(rows) + "\n\n"
        f"{len(rows)} mutations, {len(rows) - len(survivors)} caught; "
        f"{total:.0f} s in total (control {timings['control']:.0f} s)\n"
        + "\n".join(details))
    print(f"written {out / 'results.md'}")
    if survivors:
        print(f"surviving mutations (no test fails): {', '.join(survivors)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
