#!/usr/bin/env python3
"""Cross-checks aras-urdf against Pinocchio on the URDFs of example-robot-data.

Run through `cargo xtask check-urdf`, which builds the `urdf_torques`
example of aras-urdf, creates a throwaway virtual environment with `pin`,
`example-robot-data` and `numpy` from PyPI and calls this script with it
(docs/urdf.md). For each robot:

1. ≥ 1000 random states (positions within the joint limits, rates and
   accelerations of a fast motion), a fixed base turned by `BASE_RPY` and a
   tilted gravity `GRAVITY` (world frame; Pinocchio gets it in the root
   frame, Rᵀ g).
2. Our RNEA and our regressor · π against Pinocchio's `rnea` and
   `computeJointTorqueRegressor` · π, π Pinocchio's dynamic parameters
   (`toDynamicParameters`, which must equal ours), to `TAU_TOL`; the
   regressors themselves entry by entry.
3. Our base-parameter count (aras-ident on our stacked regressor) against
   the numerical rank of Pinocchio's stacked regressor (column-scaled SVD).
4. Our MJCF export (`UrdfModel::to_mjcf`, with viscous damping and armature
   of random sizes) loaded in MuJoCo: its inverse dynamics (`mj_inverse`)
   against our RNEA with the same joint columns, to `MUJOCO_TOL`, and its
   body positions against our forward kinematics (base placement and
   orientation included), to `POSITION_TOL`.

The robots: the Panda with its fingers fixed (7 joints, the hand merged into
link 7), the Panda with free fingers (9 joints, two prismatic; the `<mimic>`
removed, as Pinocchio itself reads it without `mimic=True`) and the UR5.
Joints and parameter blocks are matched by joint name, so the two joint
orders need not agree. Exits non-zero on any failure.
"""

import argparse
import json
import os
import subprocess
import sys
import time

import mujoco
import numpy as np
import pinocchio as pin

# Both sides evaluate the same rigid-body dynamics in double precision; the
# torques are O(10–100) N·m, so rounding differences are near 1e-12 N·m;
# the acceptance bound (docs/urdf.md):
TAU_TOL = 1e-9
# Dynamic parameters: the same inertials merged by the same formulas.
PARAM_TOL = 1e-12
# Rank: singular values of the column-scaled stacked regressor below this
# fraction of the largest count as zero (aras-ident's default 1e-8).
RANK_TOL = 1e-8
# MuJoCo's inverse dynamics of our MJCF: the acceptance bound (the text's
# shortest round-trip numbers carry every bit, so the agreement is near
# rounding).
MUJOCO_TOL = 1e-6
# Body positions of the MJCF in MuJoCo against our forward kinematics (the
# base placement included), m: rounding of a few chained transforms.
POSITION_TOL = 1e-12
STATES = 1000
GRAVITY = [1.3, -0.8, -9.7]
BASE_RPY = [0.2, -0.15, 0.4]
# Where the base sits (torques do not depend on it; the MJCF must carry it).
BASE_XYZ = [0.3, -0.2, 0.5]
SEED = 20261121


def robots_dir():
    """The example-robot-data robots folder (in the wheels' cmeel prefix)."""
    for dirpath, dirnames, _ in os.walk(sys.prefix):
        if dirpath.endswith(os.path.join("share", "example-robot-data", "robots")):
            return dirpath
        dirnames[:] = [d for d in dirnames if d != "__pycache__"]
    sys.exit("check-urdf: example-robot-data's robots folder not found under " + sys.prefix)


def variants(robots, work):
    """(name, urdf path) of each robot checked, variants written to `work`."""
    panda = open(os.path.join(robots, "panda_description/urdf/panda.urdf")).read()
    fixed = panda.replace('name="panda_finger_joint1" type="prismatic"', 'name="panda_finger_joint1" type="fixed"')
    fixed = fixed.replace('name="panda_finger_joint2" type="prismatic"', 'name="panda_finger_joint2" type="fixed"')
    fixed = fixed.replace('<mimic joint="panda_finger_joint1"/>', "")
    free = panda.replace('<mimic joint="panda_finger_joint1"/>', "")
    out = []
    for name, text in [("panda", fixed), ("panda-fingers", free)]:
        path = os.path.join(work, name + ".urdf")
        with open(path, "w") as f:
            f.write(text)
        out.append((name, path))
    out.append(("ur5", os.path.join(robots, "ur_description/urdf/ur5_robot.urdf")))
    return out


def states(model, joint_names, rng):
    """Random states in our joint order: q within the limits, q̇, q̈."""
    lo, hi = [], []
    for name in joint_names:
        j = model.joints[model.getJointId(name)]
        if j.nq == 1:
            a, b = model.lowerPositionLimit[j.idx_q], model.upperPositionLimit[j.idx_q]
            a, b = (a, b) if np.isfinite(a) and np.isfinite(b) and b > a else (-np.pi, np.pi)
        else:
            a, b = -np.pi, np.pi
        lo.append(a)
        hi.append(b)
    n = len(joint_names)
    q = rng.uniform(lo, hi, size=(STATES, n))
    qd = rng.uniform(-2.0, 2.0, size=(STATES, n))
    qdd = rng.uniform(-8.0, 8.0, size=(STATES, n))
    return q, qd, qdd


def to_pin(model, joint_names, q, qd, qdd):
    """Our (q, q̇, q̈) in Pinocchio's vectors (continuous joints: cos, sin)."""
    pq, pv, pa = pin.neutral(model), np.zeros(model.nv), np.zeros(model.nv)
    for k, name in enumerate(joint_names):
        j = model.joints[model.getJointId(name)]
        if j.nq == 1:
            pq[j.idx_q] = q[k]
        else:
            pq[j.idx_q : j.idx_q + 2] = [np.cos(q[k]), np.sin(q[k])]
        pv[j.idx_v] = qd[k]
        pa[j.idx_v] = qdd[k]
    return pq, pv, pa


def check(name, urdf, ours_bin, work, rng):
    model = pin.buildModelFromUrdf(urdf)
    data = model.createData()
    rot = pin.rpy.rpyToMatrix(np.array(BASE_RPY))
    model.gravity.linear = rot.T @ np.array(GRAVITY)
    joint_names = [model.names[i] for i in range(1, model.njoints)]
    def ours_for(q, qd, qdd, joint_values=None, mjcf=None):
        columns = joint_values is not None
        request = {
            "urdf": urdf,
            "settings": {
                "gravity": GRAVITY,
                "base_rpy": BASE_RPY,
                "base_xyz": BASE_XYZ,
                "columns": {"viscous": columns, "coulomb": False, "offset": False, "armature": columns},
            },
            "q": q.tolist(),
            "q_dot": qd.tolist(),
            "q_ddot": qdd.tolist(),
        }
        if columns:
            request["joint_values"] = joint_values
            request["mjcf"] = mjcf
        inp = os.path.join(work, name + ".in.json")
        outp = os.path.join(work, name + ".out.json")
        for path in (inp, outp):
            if os.path.exists(path):
                os.remove(path)
        with open(inp, "w") as f:
            json.dump(request, f)
        subprocess.run([ours_bin, inp, outp], check=True)
        with open(outp) as f:
            return json.load(f)

    # Our joint order first (a tree's may differ from Pinocchio's), then
    # the states in it.
    q, qd, qdd = states(model, joint_names, rng)
    order = ours_for(q[:20], qd[:20], qdd[:20])["joint_names"]
    if sorted(order) != sorted(joint_names):
        return [f"{name}: joints differ: ours {order}, Pinocchio {joint_names}"]
    perm = [joint_names.index(j) for j in order]
    q, qd, qdd = q[:, perm], qd[:, perm], qdd[:, perm]
    ours = ours_for(q, qd, qdd)
    failures = []
    n = len(order)
    pin_idx = [model.getJointId(j) for j in order]
    # Parameters: our blocks in our joint order, Pinocchio's per joint id.
    pi_pin = np.concatenate([model.inertias[i].toDynamicParameters() for i in range(1, model.njoints)])
    pi_ours = np.array(ours["parameters"])
    cols = [10 * (i - 1) + c for i in pin_idx for c in range(10)]
    dp = np.max(np.abs(pi_ours - pi_pin[cols]))
    if dp > PARAM_TOL * max(1.0, np.max(np.abs(pi_pin))):
        failures.append(f"{name}: dynamic parameters differ by {dp:.3e}")
    tau_err = reg_err = y_err = 0.0
    stacked = []
    for s in range(STATES):
        pq, pv, pa = to_pin(model, order, q[s], qd[s], qdd[s])
        tau_pin = pin.rnea(model, data, pq, pv, pa)
        y_pin = pin.computeJointTorqueRegressor(model, data, pq, pv, pa)
        rows = [model.joints[i].idx_v for i in pin_idx]
        tau_pin = tau_pin[rows]
        y_pin = y_pin[rows][:, cols]
        y_ours = np.array(ours["regressor"][s]).reshape(n, -1)
        tau_ours = np.array(ours["tau"][s])
        tau_err = max(tau_err, np.max(np.abs(tau_ours - tau_pin)))
        reg_err = max(reg_err, np.max(np.abs(y_ours @ pi_pin[cols] - y_pin @ pi_pin[cols])))
        y_err = max(y_err, np.max(np.abs(y_ours - y_pin)))
        stacked.append(y_pin)
    # Pinocchio's regressor time per state (its C++ call from this loop,
    # so the Python call overhead, ~1 µs, is included): printed beside
    # the figure of our bench (`cargo bench -p aras-urdf --bench regressor`).
    reps = min(STATES, 500)
    args = [to_pin(model, order, q[s], qd[s], qdd[s]) for s in range(reps)]
    start = time.perf_counter()
    for pq, pv, pa in args:
        pin.computeJointTorqueRegressor(model, data, pq, pv, pa)
    per_state_us = 1e6 * (time.perf_counter() - start) / reps
    w = np.vstack(stacked)
    norms = np.linalg.norm(w, axis=0)
    keep = norms > 1e-12 * np.max(norms)
    sv = np.linalg.svd(w[:, keep] / norms[keep], compute_uv=False)
    rank = int(np.sum(sv > RANK_TOL * sv[0]))
    gap = (sv[rank - 1], sv[rank] if rank < len(sv) else 0.0)
    print(
        f"{name}: {n} joints, {STATES} states | max |τ − rnea| {tau_err:.2e} N·m | "
        f"max |Yπ − Y_pin π| {reg_err:.2e} N·m | max |Y − Y_pin| {y_err:.2e} | "
        f"parameters {dp:.1e} | base parameters {ours['base_parameters']}, Pinocchio rank {rank} "
        f"(σ {gap[0] / sv[0]:.1e} kept, {gap[1] / sv[0]:.1e} dropped) | "
        f"Pinocchio's regressor {per_state_us:.2f} µs per state"
    )
    if tau_err > TAU_TOL:
        failures.append(f"{name}: RNEA differs from Pinocchio's by {tau_err:.3e} N·m")
    if reg_err > TAU_TOL:
        failures.append(f"{name}: regressor·π differs from Pinocchio's by {reg_err:.3e} N·m")
    if ours["base_parameters"] != rank:
        failures.append(f"{name}: {ours['base_parameters']} base parameters, Pinocchio's rank {rank}")
    failures += check_mujoco(name, order, q, qd, qdd, ours_for, work, rng)
    return failures


def check_mujoco(name, order, q, qd, qdd, ours_for, work, rng):
    """Our MJCF in MuJoCo: mj_inverse against our RNEA, viscous damping and
    armature included."""
    n = len(order)
    fv = rng.uniform(0.1, 2.0, n)
    ia = rng.uniform(0.01, 0.5, n)
    values = [v for j in range(n) for v in (fv[j], ia[j])]
    mjcf = os.path.join(work, name + ".xml")
    if os.path.exists(mjcf):
        os.remove(mjcf)
    ours = ours_for(q, qd, qdd, values, mjcf)
    model = mujoco.MjModel.from_xml_path(mjcf)
    data = mujoco.MjData(model)
    qadr = [model.joint(j).qposadr[0] for j in order]
    vadr = [model.joint(j).dofadr[0] for j in order]
    links = ours_for(q[:1], qd[:1], qdd[:1])["parameter_names"]
    bodies = [model.body(p.split(".")[0]).id for p in links[: 10 * n : 10]]
    err = pos_err = 0.0
    for s in range(len(q)):
        data.qpos[qadr] = q[s]
        data.qvel[vadr] = qd[s]
        data.qacc[vadr] = qdd[s]
        mujoco.mj_inverse(model, data)
        err = max(err, np.max(np.abs(data.qfrc_inverse[vadr] - np.array(ours["tau"][s]))))
        pos_err = max(pos_err, np.max(np.abs(data.xpos[bodies] - np.array(ours["positions"][s]))))
    print(
        f"{name}: MuJoCo {mujoco.__version__} on our MJCF, {len(q)} states | max |τ − mj_inverse| {err:.2e} N·m | "
        f"max |body position − ours| {pos_err:.2e} m"
    )
    failures = []
    if err > MUJOCO_TOL:
        failures.append(f"{name}: MuJoCo's inverse dynamics of our MJCF differs by {err:.3e} N·m")
    if pos_err > POSITION_TOL:
        failures.append(f"{name}: MuJoCo's body positions of our MJCF differ by {pos_err:.3e} m")
    return failures


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ours", required=True, help="the urdf_torques example binary")
    ap.add_argument("--work", required=True, help="a scratch directory")
    args = ap.parse_args()
    rng = np.random.default_rng(SEED)
    failures = []
    for name, urdf in variants(robots_dir(), args.work):
        failures += check(name, urdf, args.ours, args.work, rng)
    for f in failures:
        print("FAILED: " + f)
    print(f"check-urdf: {'failed' if failures else 'passed'}, Pinocchio {pin.__version__}, MuJoCo {mujoco.__version__}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
