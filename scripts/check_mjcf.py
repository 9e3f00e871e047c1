#!/usr/bin/env python3
"""Verifies the MJCF export of `aras export-mjcf` in MuJoCo itself.

Run through `cargo xtask check-mjcf`, which builds `aras`, creates a
throwaway virtual environment with `mujoco` and `numpy` from PyPI and calls
this script with it (docs/mjcf.md). For each parameter file:

1. `aras export-mjcf` → robot.xml; MuJoCo loads it without a warning, and
   its compiled masses, centres of mass and inertias give back the file's
   standard parameters (parallel-axis theorem).
2. `aras simulate` (ideal sensors) tracks (79) at 0.7 Hz and the default
   excitation; `aras predict` gives the model torques at the logged
   (θ, θ̇, θ̈). MuJoCo's constrained inverse dynamics at the same samples
   must give the same motor torques to 1e-6 N·m.
3. MuJoCo simulates the exported robot under the same PD controller and
   reference as `aras simulate`; the joint angles must agree within the
   stated tolerance.

Constrained inverse dynamics in MuJoCo. The exported tree has the dofs
q = [θ1, q_c, θ2, q_b]; the `connect` equality closes the loop with rows
J(q) q̇ = 0. For given motor motion (θ, θ̇, θ̈) the passive dofs are found
from MuJoCo's own kinematics: q_b, q_c by Gauss-Newton on the connect
residual, q̇_p = −J_p⁺ J_θ θ̇, q̈_p = −J_p⁺ (J_θ θ̈ + J̇ q̇) (mj_jac, mj_jacDot).
`mj_inverse` (constraints off, RK4 so no discrete-time correction) gives
the open-tree forces f = M q̈ + c − f_passive (damping, stiffness). The
motor torques are τ = Sᵀ f with S = ∂q̇/∂θ̇ = [I; −J_p⁺ J_θ], which removes
the loop's constraint forces (J S = 0, so Sᵀ Jᵀ λ = 0): virtual work, as in
(33), docs/model.md. MuJoCo's `frictionloss` is a soft constraint (a regularised
Coulomb force, not an explicit function of θ̇), so it is compared as
dof_frictionloss · sign(θ̇), read from the compiled model.
"""

import argparse
import contextlib
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import mujoco
import numpy as np

# Tolerances, each with its reason.
# Inverse dynamics: both sides evaluate the same rigid-body physics in
# double precision at the same samples; the torques are O(1) N·m, so
# agreement is expected near 1e-12 N·m. The bound is 1e-6 N·m.
TAU_TOL = 1e-6
# Compiled inertials: MuJoCo diagonalises `fullinertia` iteratively and
# stores float64; the round trip to I_O is good to about 1e-12 relative.
INERTIA_REL_TOL = 1e-9
# Forward simulation: see `tracking_tolerance` (derived, not tuned).

# The controller and sensors, written into the simulate config and used by
# the MuJoCo run: one source for both.
SIM = {
    "rate_hz": 1000.0,
    "substeps": 2,
    "kp": [30.0, 30.0],
    "kd": [0.3, 0.3],
    "velocity_cutoff_hz": 30.0,
    "torque_limit": [2.4, 2.4],
    "friction_smoothing": 0.03,
    "current_noise_std_a": [0.0, 0.0],
    "gear_ratios": [10.0, 10.0],
    # Ideal encoder: 6e-10 rad joint resolution.
    "counts_per_rev": [1000000000, 1000000000],
    # No lead-in: the MuJoCo twin starts from the trajectory's start at
    # t = 0, as the logged run then does.
    "lead_in_s": 0.0,
}


def run(cmd, **kw):
    """Runs a command; on failure prints its output and stops."""
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        sys.stderr.write(f"command failed: {' '.join(map(str, cmd))}\n{r.stdout}{r.stderr}")
        sys.exit(1)
    return r


@contextlib.contextmanager
def captured_stderr():
    """Captures what C code writes to fd 2 (MuJoCo prints its warnings there)."""
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile(mode="w+b") as f:
        os.dup2(f.fileno(), 2)
        out = {"text": ""}
        try:
            yield out
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            f.seek(0)
            out["text"] = f.read().decode(errors="replace")


def toml_config(params_path):
    s = SIM
    lst = lambda v: "[" + ", ".join(repr(x) for x in v) + "]"
    return (
        f"[robot]\nparams = {json.dumps(os.path.abspath(params_path))}\n"
        f"[simulation]\nperiods = PERIODS\nrate_hz = {s['rate_hz']}\nsubsteps = {s['substeps']}\n"
        f"kp = {lst(s['kp'])}\nkd = {lst(s['kd'])}\nvelocity_cutoff_hz = {s['velocity_cutoff_hz']}\n"
        f"torque_limit = {lst(s['torque_limit'])}\nfriction_smoothing = {s['friction_smoothing']}\n"
        f"current_noise_std_a = {lst(s['current_noise_std_a'])}\n"
        f"gear_ratios = {lst(s['gear_ratios'])}\ncounts_per_rev = {lst(s['counts_per_rev'])}\n"
        f"lead_in_s = {s['lead_in_s']}\n"
        "[signal]\ncutoff_hz = 0\n"
    )


def read_csv(path):
    rows = [ln for ln in open(path) if ln.strip() and not ln.lstrip().startswith("#")]
    head = [h.strip().lower() for h in rows[0].split(",")]
    data = np.array([[float(x) for x in ln.split(",")] for ln in rows[1:]])
    return {h: data[:, i] for i, h in enumerate(head)}


# ---------------------------------------------------------------- reference


class Reference:
    """Desired task motion X(t), Ẋ(t) and motor motion by (1)–(11) (docs/kinematics.md)."""

    def __init__(self, alpha, beta, kind, arg):
        self.sa, self.ca = math.sin(alpha), math.cos(alpha)
        self.cb = math.cos(beta)
        self.kind, self.arg = kind, arg

    def task(self, t):
        if self.kind == "79":  # (79): φ = 30° cos ωt + 85°, γ = 20° sin ωt + 60°
            w = 2 * math.pi * self.arg
            d = math.radians
            return (
                d(30) * math.cos(w * t) + d(85),
                d(20) * math.sin(w * t) + d(60),
                -d(30) * w * math.sin(w * t),
                d(20) * w * math.cos(w * t),
            )
        tr = self.arg  # Fourier series (74)–(75)
        x = list(tr["offset"])
        v = [0.0, 0.0]
        for l in range(len(tr["a"][0])):
            w = tr["omega_f"] * (l + 1)
            s, c = math.sin(w * t), math.cos(w * t)
            for i in range(2):
                a, b = tr["a"][i][l], tr["b"][i][l]
                x[i] += (a * s - b * c) / w
                v[i] += a * c + b * s
        return x[0], x[1], v[0], v[1]

    def motors(self, t):
        phi, gam, dphi, dgam = self.task(t)
        sg, cg = math.sin(gam), math.cos(gam)
        ca_ = (self.cb - cg * self.ca) / (sg * self.sa)
        A = math.acos(ca_)
        K = -(self.ca / self.sa - ca_ * cg / sg) / math.sin(A)  # dA/dγ
        th = np.array([phi + A, phi - A])
        thd = np.array([dphi + K * dgam, dphi - K * dgam])
        return th, thd


# ---------------------------------------------------------------- MuJoCo side


class Robot:
    def __init__(self, xml_path):
        with captured_stderr() as err:
            self.m = mujoco.MjModel.from_xml_path(xml_path)
        self.compile_output = err["text"]
        m = self.m
        self.d = mujoco.MjData(m)
        jq = lambda n: m.joint(n).qposadr[0]
        jv = lambda n: m.joint(n).dofadr[0]
        self.q_motor = [jq("theta1"), jq("theta2")]
        self.q_pass = [jq("hinge_b"), jq("hinge_c")]
        self.v_motor = [jv("theta1"), jv("theta2")]
        self.v_pass = [jv("hinge_b"), jv("hinge_c")]
        self.b3, self.b4 = m.body("link3").id, m.body("link4").id
        assert m.neq == 1 and m.eq_type[0] == mujoco.mjtEq.mjEQ_CONNECT
        self.anchor3 = m.eq_data[0][0:3].copy()
        self.anchor4 = m.eq_data[0][3:6].copy()
        self.frictionloss = m.dof_frictionloss[self.v_motor].copy()
        # Inverse dynamics: the open tree (constraints off), continuous time.
        self.mi = mujoco.MjModel.from_xml_path(xml_path)
        self.mi.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
        self.mi.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
        self.di = mujoco.MjData(self.mi)
        mujoco.mj_resetDataKeyframe(m, self.d, m.key("home").id)
        self.passive = self.d.qpos[self.q_pass].copy()

    def points(self, d):
        p3 = d.xpos[self.b3] + d.xmat[self.b3].reshape(3, 3) @ self.anchor3
        p4 = d.xpos[self.b4] + d.xmat[self.b4].reshape(3, 3) @ self.anchor4
        return p3, p4

    def loop_jacobian(self, d):
        p3, p4 = self.points(d)
        j3 = np.zeros((3, self.m.nv))
        j4 = np.zeros((3, self.m.nv))
        mujoco.mj_jac(self.m, d, j3, None, p3, self.b3)
        mujoco.mj_jac(self.m, d, j4, None, p4, self.b4)
        return j3 - j4, p3 - p4

    def loop_jacobian_dot(self, d):
        p3, p4 = self.points(d)
        j3 = np.zeros((3, self.m.nv))
        j4 = np.zeros((3, self.m.nv))
        mujoco.mj_jacDot(self.m, d, j3, None, p3, self.b3)
        mujoco.mj_jacDot(self.m, d, j4, None, p4, self.b4)
        return j3 - j4

    def close_loop(self, d, theta, guess):
        """Passive angles that close the loop at motor angles θ (Gauss-Newton)."""
        d.qpos[self.q_motor] = theta
        d.qpos[self.q_pass] = guess
        for _ in range(60):
            mujoco.mj_kinematics(self.m, d)
            mujoco.mj_comPos(self.m, d)
            jac, r = self.loop_jacobian(d)
            if np.linalg.norm(r) < 1e-15:
                break
            dq = np.linalg.lstsq(jac[:, self.v_pass], -r, rcond=None)[0]
            d.qpos[self.q_pass] += dq
            if np.linalg.norm(dq) < 1e-15:
                mujoco.mj_kinematics(self.m, d)
                mujoco.mj_comPos(self.m, d)
                break
        jac, r = self.loop_jacobian(d)
        if np.linalg.norm(r) > 1e-12:
            raise RuntimeError(f"loop does not close at theta = {theta}: residual {r}")
        return jac

    def seed_passive(self, theta):
        """Continuation from the home keyframe to θ (robust first guess)."""
        d = self.d
        mujoco.mj_resetDataKeyframe(self.m, d, self.m.key("home").id)
        th0 = d.qpos[self.q_motor].copy()
        guess = d.qpos[self.q_pass].copy()
        for s in np.linspace(0, 1, 41)[1:]:
            self.close_loop(d, th0 + s * (np.asarray(theta) - th0), guess)
            guess = d.qpos[self.q_pass].copy()
        self.passive = guess
        return guess

    def motion_map(self, jac):
        """S = ∂q̇/∂θ̇ (nv × 2) and the passive block −J_p⁺ J_θ."""
        jp, jt = jac[:, self.v_pass], jac[:, self.v_motor]
        g = -np.linalg.lstsq(jp, jt, rcond=None)[0]
        s = np.zeros((self.m.nv, 2))
        s[self.v_motor, [0, 1]] = 1.0
        s[self.v_pass, :] = g
        return s, jp

    def inverse(self, theta, theta_dot, theta_ddot):
        """Motor torques of MuJoCo's constrained inverse dynamics."""
        m, d = self.m, self.d
        jac = self.close_loop(d, theta, self.passive)
        self.passive = d.qpos[self.q_pass].copy()
        s, jp = self.motion_map(jac)
        d.qvel[:] = s @ theta_dot
        mujoco.mj_comVel(m, d)
        jdot = self.loop_jacobian_dot(d)
        rhs = jac[:, self.v_motor] @ theta_ddot + jdot @ d.qvel
        qacc = np.zeros(m.nv)
        qacc[self.v_motor] = theta_ddot
        qacc[self.v_pass] = -np.linalg.lstsq(jp, rhs, rcond=None)[0]
        di = self.di
        di.qpos[:] = d.qpos
        di.qvel[:] = d.qvel
        di.qacc[:] = qacc
        mujoco.mj_inverse(self.mi, di)
        f = di.qfrc_inverse.copy()
        # Cross-check mj_inverse against M q̈ + c − f_passive.
        mq = np.zeros(m.nv)
        mujoco.mj_mulM(self.mi, di, mq, qacc)
        g = mq + di.qfrc_bias - di.qfrc_passive
        if np.max(np.abs(g - f)) > 1e-12:
            raise RuntimeError(f"mj_inverse differs from M qacc + bias - passive: {g - f}")
        # Constraint consistency of the accelerations: J q̈ + J̇ q̇ = 0.
        acc_res = np.linalg.norm(jac @ qacc + jdot @ d.qvel)
        tau = s.T @ f + self.frictionloss * np.sign(theta_dot)
        return tau, acc_res

    def simulate(self, ref, n_ticks):
        """The exported model under the PD controller of `aras simulate`."""
        m = self.m
        d = mujoco.MjData(m)
        dt = 1.0 / SIM["rate_hz"]
        steps = round(dt / m.opt.timestep)
        if abs(steps * m.opt.timestep - dt) > 1e-12:
            raise RuntimeError(f"timestep {m.opt.timestep} does not divide the control period {dt}")
        th0, thd0 = ref.motors(0.0)
        guess = self.seed_passive(th0)
        jac = self.close_loop(d, th0, guess)
        s, _ = self.motion_map(jac)
        d.qvel[:] = s @ thd0
        mujoco.mj_forward(m, d)
        res = 2 * math.pi / (np.array(SIM["counts_per_rev"], float) * np.array(SIM["gear_ratios"]))
        quant = lambda th: np.round(th / res) * res
        alpha = 1.0 - math.exp(-2 * math.pi * SIM["velocity_cutoff_hz"] * dt)
        kp, kd = np.array(SIM["kp"]), np.array(SIM["kd"])
        lim = np.array(SIM["torque_limit"])
        prev = quant(th0)
        vel = thd0.copy()
        out = np.zeros((n_ticks, 2))
        worst_loop = 0.0
        for k in range(n_ticks):
            th = d.qpos[self.q_motor].copy()
            meas = quant(th)
            if k > 0:
                vel += ((meas - prev) / dt - vel) * alpha
            prev = meas
            thd, thdd = ref.motors(k * dt)
            tau = np.clip(kp * (thd - meas) + kd * (thdd - vel), -lim, lim)
            out[k] = meas
            d.ctrl[:] = tau  # motor1 → θ1, motor2 → θ2
            for _ in range(steps):
                mujoco.mj_step(m, d)
            p3, p4 = self.points(d)
            worst_loop = max(worst_loop, float(np.linalg.norm(p3 - p4)))
        warnings = {mujoco.mjtWarning(i).name: int(w.number) for i, w in enumerate(d.warning) if w.number}
        return out, worst_loop, warnings


# ---------------------------------------------------------------- checks


def inertia_check(robot, params):
    m = robot.m
    worst = 0.0
    for k in range(1, 5):
        link = params["links"][str(k)]
        b = m.body(f"link{k}").id
        mass = m.body_mass[b]
        rho = m.body_ipos[b]
        q = m.body_iquat[b]
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, q)
        rot = rot.reshape(3, 3)
        ig = rot @ np.diag(m.body_inertia[b]) @ rot.T
        io = ig + mass * (rho @ rho * np.eye(3) - np.outer(rho, rho))
        h = mass * rho
        want_i = np.array(
            [
                [link["Ixx"], link["Ixy"], link["Ixz"]],
                [link["Ixy"], link["Iyy"], link["Iyz"]],
                [link["Ixz"], link["Iyz"], link["Izz"]],
            ]
        )
        want_h = np.array([link["hx"], link["hy"], link["hz"]])
        scale = np.linalg.norm(want_i)
        err = max(
            np.max(np.abs(io - want_i)) / scale,
            np.max(np.abs(h - want_h)) / np.linalg.norm(want_h),
            abs(mass - link["mass"]) / link["mass"],
        )
        worst = max(worst, err)
    return worst


def coefficients_check(robot, params):
    """Joint coefficients and gravity exactly as in the file."""
    m = robot.m
    f, e = params["friction"], params["elasticity"]
    pjv = params.get("extra", {}).get("passive_joint_viscous", {})
    want = {
        ("theta1", "damping"): f["Fv1"],
        ("theta1", "stiffness"): e["Ke1"],
        ("theta1", "frictionloss"): f["Fc1"],
        ("theta2", "damping"): f["Fv2"],
        ("theta2", "stiffness"): e["Ke2"],
        ("theta2", "frictionloss"): f["Fc2"],
        ("hinge_b", "damping"): pjv.get("Fpb", 0.0),
        ("hinge_c", "damping"): pjv.get("Fpc", 0.0),
    }
    bad = []
    for (joint, attr), value in want.items():
        j = m.joint(joint)
        got = {
            "damping": m.dof_damping[j.dofadr[0]],
            "stiffness": m.jnt_stiffness[j.id],
            "frictionloss": m.dof_frictionloss[j.dofadr[0]],
        }[attr]
        if got != value:
            bad.append(f"{joint}.{attr} = {got}, file {value}")
    if list(m.opt.gravity) != list(params.get("gravity", [0, -9.81, 0])):
        bad.append(f"gravity {list(m.opt.gravity)}")
    return bad


def tracking_tolerance(params):
    """Bound on |θ_MuJoCo − θ_aras| of the closed-loop runs.

    Both runs integrate the same rigid-body model under the same controller;
    they differ in the Coulomb model near velocity reversals: `aras simulate`
    smooths sign(θ̇) by tanh(θ̇/w), MuJoCo's frictionloss is a soft
    constraint. The difference is a torque of at most 2·Fc_j, acting while
    |θ̇_j| is small; the PD loop turns a torque disturbance δτ into an angle
    error of at most δτ/Kp in steady state. Bound: 2·max Fc / Kp.
    """
    fc = max(params["friction"]["Fc1"], params["friction"]["Fc2"])
    return 2.0 * fc / min(SIM["kp"])


NOT_REPRESENTED = ["torque_offset", "coulomb_asymmetry", "stribeck_friction", "cogging", "quadratic_damping"]

# Frictionless twin: the same robot with Fc = 0 in both simulators. Both
# integrate by RK4 at the same 0.5 ms step under the same zero-order-hold
# controller, so what remains is MuJoCo's soft loop constraint (closed to
# ~1e-6 m at the 0.25 m anchor, i.e. ~4e-6 rad).
TWIN_TOL = 1e-5


def representable(params):
    """The parameter file without the effects MJCF cannot hold (listed in
    the XML comment), for the comparisons."""
    p = json.loads(json.dumps(params))
    # MuJoCo's frictionloss is a hard Coulomb level: the transition widths
    # of Fc·tanh(θ̇/w) are listed in the XML comment, not simulated.
    p.get("friction", {}).pop("w", None)
    extra = p.get("extra", {})
    for k in NOT_REPRESENTED:
        extra.pop(k, None)
    if "passive_joint_viscous" in extra:
        extra["passive_joint_viscous"]["Fpd"] = 0.0
    if not extra:
        p.pop("extra", None)
    return p


def simulate_both(aras, robot, params_path, work, tag, traj_args, periods, ref):
    """`aras simulate` (ideal sensors) and MuJoCo under the same controller."""
    cfg = os.path.join(work, f"{tag}.toml")
    with open(cfg, "w") as f:
        f.write(toml_config(params_path).replace("PERIODS", str(periods)))
    log = os.path.join(work, f"{tag}.csv")
    for p in (log, os.path.splitext(log)[0] + ".json"):
        if os.path.exists(p):
            os.remove(p)
    run([aras, "simulate", "--quiet", "--config", cfg, *traj_args, "--out", log])
    lg = read_csv(log)
    t0 = time.perf_counter()
    sim, loop_err, warns = robot.simulate(ref, len(lg["t"]))
    logged = np.column_stack([lg["theta1"], lg["theta2"]])
    dth = float(np.max(np.abs(sim - logged)))
    th_d = np.array([ref.motors(t)[0] for t in lg["t"]])
    track = float(np.max(np.abs(logged - th_d)))
    return cfg, log, lg, dth, track, loop_err, warns, time.perf_counter() - t0


def check_params(aras, label, params_path, work, excitation, short=False):
    print(f"== {label}: {params_path}")
    os.makedirs(work, exist_ok=True)
    original = json.load(open(params_path))
    params = representable(original)
    rep_path = params_path  # `aras predict` and `simulate` get the same file
    if params != original:
        print("  note: effects MJCF cannot hold are left out of the comparison (see the XML comment)")
        rep_path = os.path.join(work, "representable.json")
        json.dump(params, open(rep_path, "w"), indent=1)
    twin = json.loads(json.dumps(params))
    twin["friction"]["Fc1"] = twin["friction"]["Fc2"] = 0.0
    twin_path = os.path.join(work, "frictionless.json")
    json.dump(twin, open(twin_path, "w"), indent=1)
    xml = os.path.join(work, "robot.xml")
    twin_xml = os.path.join(work, "robot_frictionless.xml")
    for p in (xml, twin_xml):
        if os.path.exists(p):
            os.remove(p)
    run([aras, "export-mjcf", "--params", params_path, "--out", xml])
    run([aras, "export-mjcf", "--params", twin_path, "--out", twin_xml])
    robot = Robot(xml)
    twin_robot = Robot(twin_xml)
    failures = []
    for r in (robot, twin_robot):
        if r.compile_output.strip():
            failures.append(f"MuJoCo printed while loading: {r.compile_output.strip()}")
    ierr = inertia_check(robot, params)
    print(f"  compiled inertials vs file: max relative error {ierr:.2e} (≤ {INERTIA_REL_TOL:g})")
    if not ierr <= INERTIA_REL_TOL:
        failures.append(f"compiled inertials differ by {ierr:.3e}")
    bad = coefficients_check(robot, params)
    if bad:
        failures.append("coefficients differ: " + "; ".join(bad))
    geo = params["geometry"]
    alpha, beta = math.radians(geo["alpha_deg"]), math.radians(geo["beta_deg"])
    cases = [
        ("v07", "(79) at 0.7 Hz", ["--frequency", "0.7"], 2, Reference(alpha, beta, "79", 0.7)),
        (
            "excite",
            "default excitation",
            ["--trajectory", excitation],
            1,
            Reference(alpha, beta, "fourier", json.load(open(excitation))),
        ),
    ]
    if short:
        cases = cases[:1]
    for tag, name, traj_args, periods, ref in cases:
        cfg, log, lg, dth, track, loop_err, warns, secs = simulate_both(
            aras, robot, rep_path, work, tag, traj_args, periods, ref
        )
        pred = os.path.join(work, f"{tag}_pred.csv")
        if os.path.exists(pred):
            os.remove(pred)
        run([aras, "predict", "--quiet", "--config", cfg, "--params", rep_path, "--data", log, "--out", pred])
        pr = read_csv(pred)
        if not np.array_equal(lg["t"], pr["t"]):
            failures.append(f"{name}: predict rows do not match the log rows")
            continue
        n = len(lg["t"])
        t0 = time.perf_counter()
        robot.seed_passive([lg["theta1"][0], lg["theta2"][0]])
        worst, worst_acc, worst_at = 0.0, 0.0, 0
        for i in range(n):
            th = np.array([lg["theta1"][i], lg["theta2"][i]])
            thd = np.array([lg["dtheta1"][i], lg["dtheta2"][i]])
            thdd = np.array([lg["ddtheta1"][i], lg["ddtheta2"][i]])
            tau, acc_res = robot.inverse(th, thd, thdd)
            e = np.max(np.abs(tau - [pr["tau1"][i], pr["tau2"][i]]))
            if e > worst:
                worst, worst_at = e, i
            worst_acc = max(worst_acc, acc_res)
        rms = math.sqrt(np.mean(np.square([pr["tau1"], pr["tau2"]])))
        print(
            f"  {name}: inverse dynamics, {n} samples: max |τ_MuJoCo − τ_aras| = {worst:.2e} N·m "
            f"(≤ {TAU_TOL:g}; torque RMS {rms:.3f} N·m; worst at t = {lg['t'][worst_at]:.3f} s; "
            f"loop acceleration residual ≤ {worst_acc:.1e} m/s²) [{time.perf_counter() - t0:.1f} s]"
        )
        if not worst <= TAU_TOL:
            failures.append(f"{name}: inverse dynamics differ by {worst:.3e} N·m")
        tol = tracking_tolerance(params)
        print(
            f"  {name}: forward simulation, {n} control periods: max |θ_MuJoCo − θ_aras| = "
            f"{dth:.2e} rad (≤ 2·Fc/Kp = {tol:.2e}; tracking error of aras itself {track:.2e} rad); "
            f"loop closure ≤ {loop_err:.1e} m; warnings {warns or 'none'} [{secs:.1f} s]"
        )
        if not dth <= tol:
            failures.append(f"{name}: forward simulations differ by {dth:.3e} rad")
        if warns:
            failures.append(f"{name}: MuJoCo warnings {warns}")
        _, _, _, dth, _, loop_err, warns, secs = simulate_both(
            aras, twin_robot, twin_path, work, tag + "_frictionless", traj_args, periods, ref
        )
        print(
            f"  {name}: frictionless twin (Fc = 0 in both): max |θ_MuJoCo − θ_aras| = {dth:.2e} rad "
            f"(≤ {TWIN_TOL:g}); loop closure ≤ {loop_err:.1e} m; warnings {warns or 'none'} [{secs:.1f} s]"
        )
        if not dth <= TWIN_TOL:
            failures.append(f"{name}: frictionless forward simulations differ by {dth:.3e} rad")
        if warns:
            failures.append(f"{name}: MuJoCo warnings {warns} (frictionless twin)")
    return failures


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--aras", required=True, help="path of the aras binary")
    ap.add_argument("--work", required=True, help="scratch directory (emptied files only)")
    ap.add_argument("--params", action="append", default=[], help="parameter file(s) to check")
    ap.add_argument(
        "--identified",
        action="store_true",
        help="also run a short `aras pipeline` and check its params.json and robot.xml",
    )
    args = ap.parse_args()
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    excitation = os.path.join(root, "fixtures", "trajectories", "default-excitation.json")
    print(f"mujoco {mujoco.__version__}, numpy {np.__version__}")
    targets = [("default robot", os.path.join(root, "fixtures", "robots", "aras-diamond.json"))]
    targets += [(f"parameter file {i + 1}", p) for i, p in enumerate(args.params)]
    if args.identified:
        out = os.path.join(args.work, "pipeline")
        cfg = os.path.join(args.work, "pipeline.toml")
        with open(cfg, "w") as f:
            f.write(
                "[trajectory]\nstarts = 2\n[simulation]\nperiods = 4\n"
                "[validation]\nfrequencies_hz = [0.5]\nperiods = 4\npd_grid = 21\npd_random = 1000\n"
            )
        t0 = time.perf_counter()
        run([args.aras, "pipeline", "--quiet", "--force", "--reproducible", "--config", cfg, "--out", out])
        print(f"short pipeline → {out}/params.json [{time.perf_counter() - t0:.1f} s]")
        if not os.path.exists(os.path.join(out, "robot.xml")):
            sys.exit("the pipeline did not write robot.xml beside params.json")
        targets.append(("identified robot (pipeline)", os.path.join(out, "params.json")))
    # Passive-hinge damping (joint damping of hinge_b, hinge_c) checked in
    # MuJoCo too, on (79) only; Fpd and cogging have no MJCF element and
    # must be listed and left out.
    extra = json.load(open(targets[0][1]))
    extra["extra"] = {
        "passive_joint_viscous": {"Fpb": 0.004, "Fpc": 0.006, "Fpd": 0.003},
        "cogging": {"cycles_per_rev": 12.0, "order": 1, "Cs1_1": 0.01, "Cc1_1": 0.0, "Cs2_1": 0.0, "Cc2_1": 0.02},
    }
    os.makedirs(args.work, exist_ok=True)
    extra_path = os.path.join(args.work, "passive-damping.json")
    json.dump(extra, open(extra_path, "w"), indent=1)
    failures = []
    for i, (label, path) in enumerate(targets):
        failures += [f"{label}: {f}" for f in check_params(args.aras, label, path, os.path.join(args.work, f"case{i}"), excitation)]
    label = "default robot with passive-hinge damping"
    failures += [
        f"{label}: {f}"
        for f in check_params(args.aras, label, extra_path, os.path.join(args.work, "case-extra"), excitation, short=True)
    ]
    xml = open(os.path.join(args.work, "case-extra", "robot.xml")).read()
    for listed in ("passive_joint_viscous: Fpd = 0.003", "cogging: cycles_per_rev = 12"):
        if listed not in xml:
            failures.append(f"{label}: the XML comment does not list `{listed}`")
    targets.append((label, extra_path))
    if failures:
        print("FAILED:\n  " + "\n  ".join(failures))
        sys.exit(1)
    print(f"check-mjcf: all {len(targets)} robots pass")


if __name__ == "__main__":
    main()
