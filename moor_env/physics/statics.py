"""Static equilibrium of the discrete model: the hanging system before release (seed 003, section 8.2, Model 1).

The residual is the net load on every free node and on the anchor, computed by the dynamics' own load kernel
(``integrate.compute_loads``) with every velocity zero, so current drag acts as a static load and the static
state is an exact rest state of the dynamic model: a release from it starts without a transient.

It is driven to zero by Newton's method with pseudo-transient continuation (switched evolution relaxation)::

    (D / tau^2 + K) dx = F(x),        tau grows as the residual falls,

all in one numba kernel. D holds the node masses and the anchor's inertia; K = -dF/dx is analytic: per segment
dT/dl q q^T + (T / l) (I - q q^T) (the elastic and geometric stiffness), the seabed's vertical stiffness, and
for the anchor J^T S J plus the geometric stiffness of its arms (a force f at axial coordinate s resists a tilt
by s (e . f)), and the current drag's change with each segment's direction (``hydro.slender_drag_dq``); the
drag's change with depth and the anchor's own drag are left out of K. The system is solved in O(N) by the block
tree elimination of ``physics/tree.py``, the anchor's five unknowns (position, two tilt angles) as the root.

The tension-only law has a kink at zero strain. The solve runs on the smoothed law
EA (e + sqrt(e^2 + s^2)) / 2 with s lowered from ``SMOOTHING_START`` to ``SMOOTHING_FINAL`` = 1e-8 (it differs
from the exact law by less than EA * 1e-8 / 2, 9 N for the 142 mm chain, on a fully slack segment, and by far
less on taut ones). The seabed contact is smoothed with it on the first levels and exact on the last. A compressed
segment keeps the axial stiffness ``SLACK_STIFFNESS`` EA / l0 in K (inexact Newton, as usual in cable statics),
so that a node between two slack segments (a fold of chain on the seabed) is not singular.

The first guess (``physics/statics_guess.py``) puts every line on its elastic catenary (the discrete model's own
equilibrium where it hangs free), so that Newton starts with the lines in tension: calm suspended scenes converge
in a few iterations, scenes in current in ten or so. A line resting on the seabed is solved first with the second
vessel where it hangs clear, then with the vessel brought back in stages. Where Newton's radius is too small (a
slack loop that must turn), rounds of implicit dynamic relaxation move the slow modes; where that fails too,
:func:`solve_equilibrium` finishes with the slow solver of ``physics/statics_relaxation.py``.
"""

from __future__ import annotations

import math
import time

import numpy as np
from tqdm.auto import tqdm

from moor_env.compile import VESSEL_SECOND
from moor_env.contact_model import without_line_anchor_contact
from moor_env.errors import ConfigError, NoEquilibrium, SimulationDiverged, StaticsNotConverged
from moor_env.physics import layout as L
from moor_env.physics import statics_relaxation
from moor_env.physics._jit import jit_step
from moor_env.physics.anchor import rotate_axis
from moor_env.physics.environment import current_velocity
from moor_env.physics.hydro import slender_drag_dq
from moor_env.physics.integrate import INTEGRATOR_IMPLICIT_EULER, compute_loads, set_constrained_nodes
from moor_env.physics.linalg3 import inverse3
from moor_env.physics.line import segment_axis
from moor_env.physics.statics_guess import first_guess, suspending_offset_m
from moor_env.physics.statics_relaxation import StaticsReport
from moor_env.physics.tree import OR_EFF, OR_ORDER, TR_DEG, TR_NB, TR_SEG, build_tree, order

SMOOTHING_START = 1e-6
SMOOTHING_FINAL = 1e-8
# seabed contact smoothed over 1 cm on the first level, 1 mm on the next, exact on the final one
SEABED_SMOOTHING_M_PER_STRAIN = 1e4
SLACK_STIFFNESS = 1.0  # axial stiffness of a compressed segment in K, as a fraction of EA / l0
PHASE_ITERATIONS = 30  # iterations on one smoothing level before it is lowered anyway
MAX_ROTATION_RAD = 0.2  # largest anchor tilt change per Newton step
TAU_START_S = 10.0
TAU_MAX_S = 1e12
WATCHDOG_ITERATIONS = 8
STEP_TOLERANCE_M = 1e-4  # converged once the residual is within tolerance and the last Newton step below this

# ctl slots: the kernel's controls and the state it hands back between calls
C_TAU = 0
C_SMOOTHING = 1
C_TOL = 2
C_MAX_STEP = 3
C_ITERATIONS = 4  # total Newton iterations so far
C_STATUS = 5
C_RESIDUAL = 6  # largest |residual| / weight scale of the last evaluation
C_PHASE_IT = 7
C_BEST = 8  # best sum of squared scaled residuals on the current smoothing level (0: none yet)
C_SINCE_BEST = 9  # iterations since it
C_LAST_STEP = 10  # largest node move of the last Newton step [m]
N_CTL = 11

STATUS_RUNNING = 0
STATUS_CONVERGED = 1
STATUS_NONFINITE = 2


@jit_step
def _basis(body_state, basis):
    """Two unit vectors perpendicular to the anchor axis (the tilt unknowns rotate about them)."""
    ex = body_state[L.BS_AXIS]
    ey = body_state[L.BS_AXIS + 1]
    ez = body_state[L.BS_AXIS + 2]
    tx, ty, tz = (1.0, 0.0, 0.0) if abs(ex) < 0.9 else (0.0, 1.0, 0.0)
    ux = ey * tz - ez * ty
    uy = ez * tx - ex * tz
    uz = ex * ty - ey * tx
    norm = math.sqrt(ux * ux + uy * uy + uz * uz)
    basis[0, 0] = ux / norm
    basis[0, 1] = uy / norm
    basis[0, 2] = uz / norm
    basis[1, 0] = ey * basis[0, 2] - ez * basis[0, 1]
    basis[1, 1] = ez * basis[0, 0] - ex * basis[0, 2]
    basis[1, 2] = ex * basis[0, 1] - ey * basis[0, 0]


@jit_step
def _set_smoothing(env_f, slack):
    """The statics-only smoothing of the tension-only law (strain scale ``slack``) and of the seabed contact
    (penetration scale ``SEABED_SMOOTHING_M_PER_STRAIN * slack``): both kinks relax and sharpen together, and
    the final level solves on the exact contact."""
    env_f[L.EF_SLACK_SMOOTHING] = slack
    final = slack <= SMOOTHING_FINAL * 1.0001
    env_f[L.EF_SEABED_SMOOTHING] = 0.0 if final else SEABED_SMOOTHING_M_PER_STRAIN * slack


@jit_step
def _residual(body_node, basis, res_body, node_pos, node_vel, body_state, body_active, node_i, node_f, seg_i,
              seg_f, mat_f, line_f, body_f, body_q, env_f, current_profile, tracks, node_force, node_mm, node_mass,
              node_contact, seg_tension, body_load, body_acc, model, state):
    """Loads at the current state (velocities zero); returns (sum of squared scaled residuals, largest one).

    A node's residual is scaled by its weight, the anchor's force by its weight and its moments by its weight
    times its length. ``model``, ``state``: the simulator's records (``physics/records.py``) of the same arrays.
    """
    set_constrained_nodes(model, state, 0.0)
    compute_loads(model, state)
    g = env_f[L.EF_G]
    norm2 = 0.0
    worst = 0.0
    for n in range(node_i.shape[0]):
        if node_i[n, L.NI_KIND] != L.NODE_FREE:
            continue
        scale = max(node_mass[n], 1e-6) * g
        for c in range(3):
            r = abs(node_force[n, c]) / scale
            norm2 += r * r
            if not (r <= worst):
                worst = r
    if body_node >= 0:
        _basis(body_state, basis)
        weight = body_f[L.BF_WEIGHT]
        for c in range(3):
            res_body[c] = body_load[c]
        for k in range(2):
            res_body[3 + k] = (body_load[3] * basis[k, 0] + body_load[4] * basis[k, 1]
                               + body_load[5] * basis[k, 2])
        for c in range(5):
            r = abs(res_body[c]) / (weight if c < 3 else weight * body_f[L.BF_LENGTH])
            norm2 += r * r
            if not (r <= worst):
                worst = r
    return norm2, worst


@jit_step
def _add_block(dmat, n, sign, m, scale):
    """dmat[n] += sign * m * scale (3x3)."""
    for i in range(3):
        for j in range(3):
            dmat[n, i, j] += sign * scale * m[i, j]


@jit_step
def _assemble(tau, body_node, node_pos, seg_i, seg_f, mat_f, env_f, current_profile, node_mass, node_contact,
              seg_tension, dmat, coupling, orow):
    """Diagonal blocks D / tau^2 + K (``dmat``) and the couplings of every segment's two ends
    (``coupling[s, 0]`` = K_ab, ``coupling[s, 1]`` = K_ba), K = -dF/dx."""
    nn = node_pos.shape[0]
    inv_tau2 = 1.0 / (tau * tau)
    dmat[:, :, :] = 0.0
    for n in range(nn):
        if orow[n, OR_EFF] == n and n != body_node:
            m = max(node_mass[n], 1e-6) * inv_tau2
            for c in range(3):
                dmat[n, c, c] = m
    depth = env_f[L.EF_DEPTH]
    kbot = env_f[L.EF_KBOT]
    soft = env_f[L.EF_SEABED_SMOOTHING]
    for n in range(nn):
        e = orow[n, OR_EFF]
        if e < 0 or e == body_node or node_contact[n] <= 0.0:
            continue
        penetration = -depth - node_pos[n, 2]
        if soft > 0.0:  # slope of the smoothed contact (physics/seabed.py)
            slope = 0.5 * (1.0 + penetration / math.sqrt(penetration * penetration + soft * soft))
            dmat[e, 2, 2] += kbot * node_contact[n] * slope
        elif penetration >= 0.0:
            dmat[e, 2, 2] += kbot * node_contact[n]
    smoothing = env_f[L.EF_SLACK_SMOOTHING]
    rho = env_f[L.EF_RHO]
    kmat = np.empty((3, 3))
    dq = np.empty((3, 3))
    for s in range(seg_i.shape[0]):
        coupling[s, :, :, :] = 0.0
        if seg_i[s, L.SI_ACTIVE] == 0:
            continue
        a = seg_i[s, L.SI_A]
        b = seg_i[s, L.SI_B]
        ea = orow[a, OR_EFF]
        eb = orow[b, OR_EFF]
        if ea == eb:
            continue
        mat = seg_i[s, L.SI_MAT]
        ea_n = mat_f[mat, L.MF_EA]
        l0 = seg_f[s, L.SF_L0]
        length, qx, qy, qz = segment_axis(node_pos, a, b)
        q = (qx, qy, qz)
        strain = (length - l0) / l0
        if smoothing > 0.0:
            slope = 0.5 * ea_n * (1.0 + strain / math.sqrt(strain * strain + smoothing * smoothing))
        else:
            slope = ea_n if strain > 0.0 else 0.0
        if strain <= 0.0:
            slope = max(slope, SLACK_STIFFNESS * ea_n)
        kq = slope / l0
        kt = seg_tension[s] / length if length > 0.0 else 0.0
        for i in range(3):
            for j in range(3):
                kmat[i, j] = (kq - kt) * q[i] * q[j] + (kt if i == j else 0.0)
        if ea >= 0:
            _add_block(dmat, ea, 1.0, kmat, 1.0)
        if eb >= 0:
            _add_block(dmat, eb, 1.0, kmat, 1.0)
        _add_block(coupling[s], 0, -1.0, kmat, 1.0)
        _add_block(coupling[s], 1, -1.0, kmat, 1.0)
        # current drag turns with the segment: d f_end / d x_b = D_end P / length, d / d x_a = -D_end P / length
        if env_f[L.EF_CUR_SCALE] == 0.0 or length <= 0.0:
            continue
        d = mat_f[mat, L.MF_D]
        cn = 0.25 * rho * mat_f[mat, L.MF_CDN] * d * l0
        ct = 0.25 * rho * mat_f[mat, L.MF_CDT] * math.pi * d * l0
        for end in range(2):
            node = a if end == 0 else b
            ux, uy, uz = current_velocity(node_pos[node, 2], env_f, current_profile)
            slender_drag_dq(ux, uy, uz, qx, qy, qz, cn, ct, dq)
            for i in range(3):
                for j in range(3):
                    kmat[i, j] = (dq[i, j] - (dq[i, 0] * q[0] + dq[i, 1] * q[1] + dq[i, 2] * q[2]) * q[j]) / length
            # K = -dF/dx: this end's row gets +D P / l from x_a and -D P / l from x_b
            if end == 0:
                if ea >= 0:
                    _add_block(dmat, ea, 1.0, kmat, 1.0)
                _add_block(coupling[s], 0, -1.0, kmat, 1.0)
            else:
                if eb >= 0:
                    _add_block(dmat, eb, -1.0, kmat, 1.0)
                _add_block(coupling[s], 1, 1.0, kmat, 1.0)


@jit_step
def _solve_body(tau, p, basis, res_body, body_state, node_f, node_force, body_f, smat, rho_p, dq):
    """The anchor's five unknowns from the lines' impedance ``smat`` and right-hand side ``rho_p`` at node p.

    (J^T S J + K_geo + D_b / tau^2) dq = R_b + J^T rho, with J the body node's motion per unknown (translation,
    then rotation about basis[0] and basis[1]). Writes dq and returns the body node's motion J dq in ``rho_p``.
    """
    ex = body_state[L.BS_AXIS]
    ey = body_state[L.BS_AXIS + 1]
    ez = body_state[L.BS_AXIS + 2]
    sp = node_f[p, L.NF_BODY_S]
    jac = np.zeros((3, 5))
    for c in range(3):
        jac[c, c] = 1.0
        jac[c, 3] = -sp * basis[1, c]  # s (u1 x e) = -s u2
        jac[c, 4] = sp * basis[0, c]  # s (u2 x e) = s u1
    a = jac.T @ smat @ jac
    rhs = res_body + jac.T @ rho_p
    inv_tau2 = 1.0 / (tau * tau)
    geo = sp * (ex * node_force[p, 0] + ey * node_force[p, 1] + ez * node_force[p, 2])
    geo += body_f[L.BF_S_BUOY] * body_f[L.BF_BUOYANCY] * ez
    for c in range(3):
        a[c, c] += body_f[L.BF_MASS_AXIAL] * inv_tau2
    for c in range(3, 5):
        a[c, c] += body_f[L.BF_M22] * inv_tau2 + geo
    sol = np.linalg.solve(a, rhs)
    dq[:] = sol
    rho_p[:] = jac @ sol


@jit_step
def _newton_step(tau, nq, body_node, basis, res_body, dq, node_pos, body_state, node_f, seg_i, seg_f, mat_f,
                 body_f, env_f, current_profile, node_force, node_mass, node_contact, node_acc, seg_tension, dmat,
                 coupling, tree, orow):
    """Solve (D / tau^2 + K) dx = F into node_acc (free nodes) and dq (anchor) by block elimination over the
    tree, leaves first (x_c = D_c^-1 (r_c - K_cp x_p) once the parent p is known)."""
    _assemble(tau, body_node, node_pos, seg_i, seg_f, mat_f, env_f, current_profile, node_mass, node_contact,
              seg_tension, dmat, coupling, orow)
    for n in range(node_pos.shape[0]):
        if orow[n, OR_EFF] == n:
            for c in range(3):
                node_acc[n, c] = 0.0 if n == body_node else node_force[n, c]
    inv = np.empty((3, 3))
    kpc_inv = np.empty((3, 3))
    for k in range(nq):
        c = orow[k, OR_ORDER]
        inverse3(dmat[c], inv)
        dmat[c, :, :] = inv
        node_acc[c, :] = inv @ node_acc[c]
        if tree[c, TR_DEG] != -1:
            continue
        s = tree[c, TR_SEG]
        p = tree[c, TR_NB]
        c_is_a = orow[seg_i[s, L.SI_A], OR_EFF] == c
        k_cp = coupling[s, 0] if c_is_a else coupling[s, 1]
        k_pc = coupling[s, 1] if c_is_a else coupling[s, 0]
        kpc_inv[:, :] = k_pc @ inv
        dmat[p, :, :] -= kpc_inv @ k_cp
        node_acc[p, :] -= k_pc @ node_acc[c]
    if body_node >= 0:
        rho_p = node_acc[body_node].copy()
        _solve_body(tau, body_node, basis, res_body, body_state, node_f, node_force, body_f, dmat[body_node],
                    rho_p, dq)
        node_acc[body_node, :] = rho_p
    for k in range(nq - 1, -1, -1):
        c = orow[k, OR_ORDER]
        if tree[c, TR_DEG] != -1:
            continue
        s = tree[c, TR_SEG]
        p = tree[c, TR_NB]
        k_cp = coupling[s, 0] if orow[seg_i[s, L.SI_A], OR_EFF] == c else coupling[s, 1]
        node_acc[c, :] -= dmat[c] @ (k_cp @ node_acc[p])


@jit_step
def _apply(scale, nq, body_node, basis, dq, node_i, node_f, node_pos, node_acc, body_state, axis0, saved, tree,
           orow):
    """x += scale * dx for the anchor, and for every free node along the tree from its root: each node is placed
    from its (already moved) parent along the segment's new direction at its linearly predicted length.

    Why: a segment that turns by an angle t under x += dx lengthens by l t^2 / 2, which its axial stiffness turns
    into a spurious tension EA t^2 / 2; on a slack loop that has to swing (current, a moved vessel) this confines
    plain Newton to steps of a tenth of a degree. Placing nodes by direction and length keeps the linear model's
    axial prediction; the mismatch gathers in the segments to prescribed ends, where Newton corrects it as a
    linear, axial error.
    """
    if body_node >= 0:
        for c in range(3):
            body_state[L.BS_POS + c] += scale * dq[c]
            axis0[c] = body_state[L.BS_AXIS + c]
        phx = scale * (dq[3] * basis[0, 0] + dq[4] * basis[1, 0])
        phy = scale * (dq[3] * basis[0, 1] + dq[4] * basis[1, 1])
        phz = scale * (dq[3] * basis[0, 2] + dq[4] * basis[1, 2])
        rotate_axis(body_state, axis0, phx, phy, phz, 1.0)
        sp = node_f[body_node, L.NF_BODY_S]
        for c in range(3):
            node_pos[body_node, c] = body_state[L.BS_POS + c] + sp * body_state[L.BS_AXIS + c]
    for k in range(nq - 1, -1, -1):
        c = orow[k, OR_ORDER]
        if tree[c, TR_DEG] != -1:
            for i in range(3):
                node_pos[c, i] += scale * node_acc[c, i]
            continue
        p = tree[c, TR_NB]
        old_len = math.sqrt((saved[c, 0] - saved[p, 0]) ** 2 + (saved[c, 1] - saved[p, 1]) ** 2
                            + (saved[c, 2] - saved[p, 2]) ** 2)
        # predicted relative vector and length of the segment (linear in the step, parent's linear motion)
        vx = saved[c, 0] - saved[p, 0] + scale * (node_acc[c, 0] - node_acc[p, 0])
        vy = saved[c, 1] - saved[p, 1] + scale * (node_acc[c, 1] - node_acc[p, 1])
        vz = saved[c, 2] - saved[p, 2] + scale * (node_acc[c, 2] - node_acc[p, 2])
        new_len = math.sqrt(vx * vx + vy * vy + vz * vz)
        target = old_len
        if old_len > 0.0:
            target += scale * ((saved[c, 0] - saved[p, 0]) * (node_acc[c, 0] - node_acc[p, 0])
                               + (saved[c, 1] - saved[p, 1]) * (node_acc[c, 1] - node_acc[p, 1])
                               + (saved[c, 2] - saved[p, 2]) * (node_acc[c, 2] - node_acc[p, 2])) / old_len
        if new_len <= 0.0 or target <= 0.0:
            for i in range(3):
                node_pos[c, i] += scale * node_acc[c, i]
            continue
        f = target / new_len
        node_pos[c, 0] = node_pos[p, 0] + vx * f
        node_pos[c, 1] = node_pos[p, 1] + vy * f
        node_pos[c, 2] = node_pos[p, 2] + vz * f


@jit_step
def newton_statics(ctl, max_iter, body_node, node_pos, node_vel, body_state, body_active, node_i, node_f, seg_i,
                   seg_f, mat_f, line_f, body_f, body_q, env_f, current_profile, tracks, node_force, node_mm,
                   node_mass, node_contact, node_acc, seg_tension, body_load, body_acc, pos0, vel0, best_pos,
                   best_body, model, state):
    """Up to ``max_iter`` Newton iterations of the static problem from the current state, in place.

    ``ctl`` (``C_*`` slots) carries the pseudo time step, the smoothing level, the tolerance and the step limit
    in, and the iteration count, status and residual out, so that a long solve can be run in chunks (progress).
    ``body_node``: the node attaching the lines to the anchor (the anchor is then solved for), or -1.
    """
    nn = node_i.shape[0]
    tree = pos0.view(np.int64)
    orow = vel0.view(np.int64)
    for n in range(nn):
        if node_i[n, L.NI_KIND] == L.NODE_FREE:
            for c in range(3):
                node_vel[n, c] = 0.0
    for c in range(3):
        body_state[L.BS_VEL + c] = 0.0
        body_state[L.BS_OMEGA + c] = 0.0
    build_tree(body_node, node_i, seg_i, tree, orow)
    nq = order(body_node, node_i, seg_i, tree, orow)
    dmat = np.zeros((nn, 3, 3))
    coupling = np.zeros((seg_i.shape[0], 2, 3, 3))
    saved = np.empty((nn, 3))
    saved_body = np.empty(L.N_BODY_STATE)
    basis = np.zeros((2, 3))
    res_body = np.zeros(5)
    dq = np.zeros(5)
    axis0 = np.zeros(3)
    tau = ctl[C_TAU]
    tol = ctl[C_TOL]
    _set_smoothing(env_f, ctl[C_SMOOTHING])
    norm2, worst = _residual(body_node, basis, res_body, node_pos, node_vel, body_state, body_active, node_i, node_f,
                             seg_i, seg_f, mat_f, line_f, body_f, body_q, env_f, current_profile, tracks, node_force,
                             node_mm, node_mass, node_contact, seg_tension, body_load, body_acc, model, state)
    status = STATUS_RUNNING
    if ctl[C_BEST] == 0.0 or norm2 < ctl[C_BEST]:
        ctl[C_BEST] = norm2
        best_pos[:, :] = node_pos
        best_body[:] = body_state
    for _ in range(max_iter):
        if not (worst == worst) or not (norm2 == norm2):
            status = STATUS_NONFINITE
            break
        smoothing = env_f[L.EF_SLACK_SMOOTHING]
        final = smoothing <= SMOOTHING_FINAL * 1.0001
        if worst < tol and final and ctl[C_LAST_STEP] < STEP_TOLERANCE_M:
            status = STATUS_CONVERGED
            break
        if not final and (worst < 10.0 * tol or ctl[C_PHASE_IT] >= PHASE_ITERATIONS):
            _set_smoothing(env_f, max(0.1 * smoothing, SMOOTHING_FINAL))
            ctl[C_PHASE_IT] = 0.0
            norm2, worst = _residual(body_node, basis, res_body, node_pos, node_vel, body_state, body_active, node_i,
                                     node_f, seg_i, seg_f, mat_f, line_f, body_f, body_q, env_f, current_profile,
                                     tracks, node_force, node_mm, node_mass, node_contact, seg_tension, body_load,
                                     body_acc, model, state)
            ctl[C_BEST] = norm2
            ctl[C_SINCE_BEST] = 0.0
            best_pos[:, :] = node_pos
            best_body[:] = body_state
            continue
        ctl[C_ITERATIONS] += 1.0
        ctl[C_PHASE_IT] += 1.0
        _newton_step(tau, nq, body_node, basis, res_body, dq, node_pos, body_state, node_f, seg_i, seg_f, mat_f,
                     body_f, env_f, current_profile, node_force, node_mass, node_contact, node_acc, seg_tension,
                     dmat, coupling, tree, orow)
        biggest = 0.0
        for n in range(nn):
            if node_i[n, L.NI_KIND] == L.NODE_FREE:
                for c in range(3):
                    biggest = max(biggest, abs(node_acc[n, c]))
        scale = 1.0
        if body_node >= 0:
            for c in range(3):
                biggest = max(biggest, abs(dq[c]))
            rot = math.sqrt(dq[3] * dq[3] + dq[4] * dq[4])
            if rot > MAX_ROTATION_RAD:
                scale = MAX_ROTATION_RAD / rot
        if biggest * scale > ctl[C_MAX_STEP]:
            scale = ctl[C_MAX_STEP] / biggest
        if not (scale == scale) or not (biggest == biggest):
            tau *= 0.25
            continue
        saved[:, :] = node_pos
        saved_body[:] = body_state
        _apply(scale, nq, body_node, basis, dq, node_i, node_f, node_pos, node_acc, body_state, axis0, saved, tree,
               orow)
        new2, new_worst = _residual(body_node, basis, res_body, node_pos, node_vel, body_state, body_active, node_i,
                                    node_f, seg_i, seg_f, mat_f, line_f, body_f, body_q, env_f, current_profile,
                                    tracks, node_force, node_mm, node_mass, node_contact, seg_tension, body_load,
                                    body_acc, model, state)
        if not (new2 == new2):
            # not finite: back to the saved state with a shorter pseudo time step
            node_pos[:, :] = saved
            body_state[:] = saved_body
            tau *= 0.25
            norm2, worst = _residual(body_node, basis, res_body, node_pos, node_vel, body_state, body_active, node_i,
                                     node_f, seg_i, seg_f, mat_f, line_f, body_f, body_q, env_f, current_profile,
                                     tracks, node_force, node_mm, node_mass, node_contact, seg_tension, body_load,
                                     body_acc, model, state)
            continue
        ctl[C_LAST_STEP] = biggest * scale
        norm2 = new2
        worst = new_worst
        # non-monotone: the residual may grow for a few steps (the axial mismatch the placement gathers at the
        # prescribed ends is corrected by the next step); without a new best for WATCHDOG_ITERATIONS, go back
        # to the best state with a shorter pseudo time step
        if norm2 < ctl[C_BEST]:
            ctl[C_BEST] = norm2
            ctl[C_SINCE_BEST] = 0.0
            best_pos[:, :] = node_pos
            best_body[:] = body_state
            tau = min(tau * 4.0, TAU_MAX_S)
        else:
            ctl[C_SINCE_BEST] += 1.0
            if ctl[C_SINCE_BEST] >= WATCHDOG_ITERATIONS:
                node_pos[:, :] = best_pos
                body_state[:] = best_body
                tau *= 0.1
                ctl[C_SINCE_BEST] = 0.0
                norm2, worst = _residual(body_node, basis, res_body, node_pos, node_vel, body_state, body_active,
                                         node_i, node_f, seg_i, seg_f, mat_f, line_f, body_f, body_q, env_f,
                                         current_profile, tracks, node_force, node_mm, node_mass, node_contact,
                                         seg_tension, body_load, body_acc, model, state)
    ctl[C_TAU] = tau
    ctl[C_SMOOTHING] = env_f[L.EF_SLACK_SMOOTHING]
    ctl[C_STATUS] = status
    ctl[C_RESIDUAL] = worst
    _set_smoothing(env_f, 0.0)
    return status


def body_root(sim) -> int:
    """The node that attaches the lines to the anchor when the anchor is a static unknown, else -1."""
    if not sim.model.body_active:
        return -1
    body = np.nonzero(sim.state.node_i[:, L.NI_KIND] == L.NODE_BODY)[0]
    return int(body[0]) if body.size else -1


def n_static_dofs(sim) -> int:
    """Number of unknowns of the static problem (3 per free node, 5 for a held anchor)."""
    free = int(np.count_nonzero(sim.state.node_i[:, L.NI_KIND] == L.NODE_FREE))
    return 3 * free + (5 if body_root(sim) >= 0 else 0)


CHUNK_ITERATIONS = 25
STAGE_TOLERANCE = 1e-2  # residual/weight to which a continuation stage before the last is solved
VESSEL_STEPS = 12  # a line resting on the seabed is solved first with the second vessel where it hangs clear, then
# with the vessel brought back in this many steps (the touchdown moves along the line gradually)
NEWTON_BEFORE_RELAXATION = 12  # Newton iterations from the guess before relaxing instead
NEWTON_AFTER_RELAXATION = 25
RELAXATION_S = 20.0  # pseudo time of one relaxation round
RELAXATION_DT_S = 0.25  # its implicit step: below the anchor's pendulum limit (explicit in the implicit step)
PROGRESS_AFTER_S = 1.0


def relax_implicitly(sim, duration_s: float, dt_s: float = RELAXATION_DT_S, chunk_steps: int = 4) -> None:
    """Kinetic-damping dynamic relaxation with the implicit integrator: step the dynamic model from the current
    state (vessels at their mean positions) and zero every velocity whenever the total kinetic energy starts to
    fall (it has just passed an energy peak, the best estimate of the rest position along the dominant motion).
    Robust from any state (the implicit step handles segments going slack and taut), linear in cost."""
    st, m = sim.state, sim.model
    saved = sim.dt, sim.integrator_code, sim.env_f[L.EF_SPEED_LIMIT], sim.env_f[L.EF_STRAIN_LIMIT]
    sim.dt, sim.integrator_code = dt_s, INTEGRATOR_IMPLICIT_EULER
    sim.env_f[L.EF_SPEED_LIMIT] = sim.env_f[L.EF_STRAIN_LIMIT] = 1e9
    free = st.node_i[:, L.NI_KIND] == L.NODE_FREE
    previous = 0.0
    start = st.copy()
    try:
        for _ in range(max(1, int(duration_s / (dt_s * chunk_steps)))):
            st.t = 0.0
            try:
                sim.advance_to(chunk_steps * dt_s)
            except SimulationDiverged:
                # a blow-up of the pseudo dynamics (a fine mesh at a long step): start again at half the step
                _restore(st, start)
                sim.dt *= 0.5
                if sim.dt < 1e-3:
                    raise
                previous = 0.0
                continue
            kinetic = float(np.sum(sim.work.node_mass[free] * np.sum(st.node_vel[free] ** 2, axis=1)))
            if m.body_active:
                kinetic += m.body_f[L.BF_MASS_AXIAL] * float(np.sum(st.body_state[L.BS_VEL:L.BS_VEL + 3] ** 2))
            if kinetic < previous:
                _stop(st)
                previous = 0.0
            else:
                previous = kinetic
    finally:
        sim.dt, sim.integrator_code, sim.env_f[L.EF_SPEED_LIMIT], sim.env_f[L.EF_STRAIN_LIMIT] = saved
        st.t = 0.0
        _stop(st)


def _restore(st, saved) -> None:
    for name in ("node_pos", "node_vel", "body_state", "seg_f", "line_f"):
        getattr(st, name)[...] = getattr(saved, name)


def _stop(st) -> None:
    st.node_vel[:] = 0.0
    st.body_state[L.BS_VEL:L.BS_VEL + 3] = 0.0
    st.body_state[L.BS_OMEGA:L.BS_OMEGA + 3] = 0.0


def _stages(warm: bool, current: float, offset_m: float) -> list[tuple[float, float]]:
    """(current scale, second vessel's extra distance [m]) of each continuation stage: the calm equilibrium first,
    then the current; where the line starts clear of the seabed, the vessel moves back in ``VESSEL_STEPS``."""
    if warm:
        return [(current, 0.0)]
    stages = [(0.0, offset_m)]
    if offset_m > 0.0:
        stages += [(current * k / VESSEL_STEPS, offset_m * (1.0 - k / VESSEL_STEPS))
                   for k in range(1, VESSEL_STEPS + 1)]
    elif current > 0.0:
        stages.append((current, 0.0))
    return stages


def _move_second_vessel(sim, mean_m: np.ndarray, away_m: float) -> None:
    """Put the second vessel ``away_m`` further from the installation vessel than ``mean_m`` (its mean position)."""
    u = mean_m[:2] - sim.vessel_mean_m[0, :2]
    norm = float(np.hypot(*u))
    u = u / norm if norm > 1e-9 else np.array([1.0, 0.0])
    sim.vessel_mean_m[VESSEL_SECOND] = mean_m
    sim.vessel_mean_m[VESSEL_SECOND, :2] += away_m * u
    sim.set_vessel_motion(0.0, 1.0, np.zeros(sim.vessel_mean_m.shape[0]))


def _restore_second_vessel(sim, mean_m: np.ndarray, tracks: tuple) -> None:
    """Put the second vessel and the vessel tracks back as they were before :func:`_move_second_vessel`."""
    sim.vessel_mean_m[VESSEL_SECOND] = mean_m
    sim.tracks = tracks[0]
    sim.env_f[L.EF_TRACK_T0] = tracks[1]
    sim.env_f[L.EF_TRACK_DT] = tracks[2]


def _run_chunk(sim, ctl: np.ndarray, max_iter: int, tol_rel: float, best: tuple[np.ndarray, np.ndarray]) -> int:
    """Up to ``CHUNK_ITERATIONS`` Newton iterations of the simulator's state to ``tol_rel`` (``best``: scratch for
    the best state so far)."""
    st, m, w = sim.state, sim.model, sim.work
    ctl[C_TOL] = tol_rel
    try:
        return newton_statics(ctl, min(CHUNK_ITERATIONS, max_iter - int(ctl[C_ITERATIONS])), body_root(sim),
                              st.node_pos, st.node_vel, st.body_state, m.body_active, st.node_i, st.node_f, st.seg_i,
                              st.seg_f, m.mat_f, st.line_f, m.body_f, m.body_q, sim.env_f, m.current_profile,
                              sim.tracks, w.node_force, w.node_mm, w.node_mass, w.node_contact, w.node_acc,
                              w.seg_tension, w.body_load, w.body_acc, w.pos0, w.vel0, best[0], best[1],
                              *sim.records())
    except np.linalg.LinAlgError as exc:  # the anchor's 5x5 system singular or not finite
        _set_smoothing(sim.env_f, 0.0)
        raise StaticsNotConverged(f"static Newton step failed: {exc}") from exc


METHODS = ("auto", "newton", "relaxation")


@without_line_anchor_contact
def solve_equilibrium(sim, tol_rel: float = 1e-4, max_iter: int = 600, max_step_m: float = 20.0,
                      warm: bool = False, analytic_guess: bool = True, progress: bool = True,
                      method: str = "auto") -> StaticsReport:
    """Drive the simulator's current state to static equilibrium in place.

    ``method``: "auto" runs :func:`solve_newton` and, where it does not converge, the slow, robust solver of
    ``physics/statics_relaxation.py`` from the same start; "newton" and "relaxation" run one of them only.
    Other parameters and exceptions as :func:`solve_newton`; the report's ``method`` says which solver finished.
    """
    if method not in METHODS:
        raise ConfigError("method", method, "one of " + ", ".join(METHODS))
    start = sim.state.copy()
    try:
        if method == "relaxation":
            raise StaticsNotConverged("the relaxation solver was asked for")
        return solve_newton(sim, tol_rel, max_iter, max_step_m, warm, analytic_guess, progress)
    except (StaticsNotConverged, SimulationDiverged) as exc:
        if method == "newton":
            raise _as_not_converged(exc) from exc
        _restore(sim.state, start)
        sim.state.t = start.t
    try:
        with tqdm(desc="statics (relaxation)", unit="s relaxed", disable=not progress, leave=False,
                  delay=PROGRESS_AFTER_S) as bar:
            return statics_relaxation.solve_equilibrium(sim, tol_rel=tol_rel, warm=warm,
                                                        analytic_guess=analytic_guess, tick=bar.update)
    except SimulationDiverged as exc:
        raise _as_not_converged(exc) from exc


def _as_not_converged(exc: Exception) -> StaticsNotConverged:
    """A blow-up of the pseudo dynamics of a static solve is a statics failure, not a simulation result."""
    if isinstance(exc, StaticsNotConverged):
        return exc
    return StaticsNotConverged(f"static solve failed: its relaxation diverged ({exc})")


@without_line_anchor_contact
def solve_newton(sim, tol_rel: float = 1e-4, max_iter: int = 600, max_step_m: float = 20.0,
                      warm: bool = False, analytic_guess: bool = True, progress: bool = True) -> StaticsReport:
    """Drive the simulator's current state to static equilibrium in place.

    Parameters
    ----------
    sim : Simulator
    tol_rel : float
        Converged when every unknown's residual is below ``tol_rel`` times its weight scale (node weight;
        anchor weight, and anchor weight times length for its moments).
    max_iter : int
        Newton iterations at most.
    max_step_m : float
        Largest node move per iteration [m].
    warm : bool
        Start from the current state on the final smoothing with a long pseudo time step (a small change of an
        equilibrium, e.g. a corrected wire length).
    analytic_guess : bool
        Start from the elastic-catenary guess (:func:`moor_env.physics.statics_guess.first_guess`); otherwise
        from the current state, however poor.
    progress : bool
        Show a progress bar once a solve has taken more than a second.

    Raises
    ------
    StaticsNotConverged
    moor_env.errors.NoEquilibrium
        From the first guess: the scene has no equilibrium (named cause and key).
    """
    n_dofs = n_static_dofs(sim)
    if n_dofs == 0:  # nothing to solve (e.g. an anchor held at its drop height, no lines)
        return StaticsReport(0, 0.0, 0.0, 0, "newton")
    mode = first_guess(sim) if analytic_guess and not warm else 0
    ctl = np.zeros(N_CTL)
    ctl[C_TAU] = 1e3 if warm else TAU_START_S
    ctl[C_SMOOTHING] = SMOOTHING_FINAL if warm else SMOOTHING_START
    ctl[C_TOL] = tol_rel
    ctl[C_MAX_STEP] = max_step_m
    ctl[C_LAST_STEP] = math.inf
    best = (np.empty_like(sim.state.node_pos), np.empty(L.N_BODY_STATE))
    current = float(sim.env_f[L.EF_CUR_SCALE])
    second = sim.vessel_mean_m[VESSEL_SECOND].copy() if sim.vessel_mean_m.shape[0] > VESSEL_SECOND else None
    tracks = (sim.tracks.copy(), sim.env_f[L.EF_TRACK_T0], sim.env_f[L.EF_TRACK_DT])
    offset = suspending_offset_m(sim) if mode != 0 and second is not None else 0.0
    t0 = time.perf_counter()
    bar = None
    try:
        if offset > 0.0:  # start with the second vessel where the line hangs clear of the seabed
            _move_second_vessel(sim, second, offset)
            try:
                first_guess(sim)
            except NoEquilibrium:  # the helper geometry is too taut: solve from the scene's own guess
                _restore_second_vessel(sim, second, tracks)
                offset = 0.0
                first_guess(sim)
        stages = _stages(warm, current, offset)
        for stage, (scale, away) in enumerate(stages):
            sim.env_f[L.EF_CUR_SCALE] = scale
            if second is not None and offset > 0.0:
                _move_second_vessel(sim, second, away)
            last = stage == len(stages) - 1
            ctl[C_STATUS] = STATUS_RUNNING
            ctl[C_BEST] = 0.0
            ctl[C_SINCE_BEST] = 0.0
            if stage > 0:  # each stage starts near the last equilibrium, on the smoothed laws again
                ctl[C_TAU] = max(ctl[C_TAU], 1e3)
                ctl[C_SMOOTHING] = SMOOTHING_START
                ctl[C_PHASE_IT] = 0.0
                ctl[C_LAST_STEP] = math.inf
            budget = NEWTON_BEFORE_RELAXATION
            while ctl[C_ITERATIONS] < max_iter:
                status = _run_chunk(sim, ctl, min(max_iter, int(ctl[C_ITERATIONS]) + budget),
                                    tol_rel if last else max(STAGE_TOLERANCE, tol_rel), best)
                if status == STATUS_CONVERGED:
                    break
                if progress and bar is None and time.perf_counter() - t0 > PROGRESS_AFTER_S:
                    bar = tqdm(total=max_iter, desc="statics", unit="it", leave=False)
                if bar is not None:
                    bar.n = int(ctl[C_ITERATIONS])
                    bar.set_postfix(residual=f"{ctl[C_RESIDUAL]:.2g}")
                    bar.refresh()
                if ctl[C_PHASE_IT] >= budget or status == STATUS_NONFINITE:
                    # Newton's radius is small where a slack loop must turn (a segment's length grows with the
                    # square of its rotation, times EA): relax the slow modes dynamically, then Newton again
                    before = sim.state.copy()
                    try:
                        relax_implicitly(sim, RELAXATION_S)
                    except SimulationDiverged:  # the pseudo dynamics blew up: Newton goes on from where it was
                        _restore(sim.state, before)
                    ctl[C_TAU] = TAU_START_S
                    ctl[C_PHASE_IT] = 0.0
                    ctl[C_BEST] = 0.0
                    ctl[C_SINCE_BEST] = 0.0
                    ctl[C_STATUS] = STATUS_RUNNING
                    budget = NEWTON_AFTER_RELAXATION
            if ctl[C_STATUS] != STATUS_CONVERGED:
                break
    finally:
        sim.env_f[L.EF_CUR_SCALE] = current
        _set_smoothing(sim.env_f, 0.0)
        if second is not None and offset > 0.0:
            _restore_second_vessel(sim, second, tracks)
        if bar is not None:
            bar.close()
        _stop(sim.state)
        sim.evaluate_loads()
    iterations = int(ctl[C_ITERATIONS])
    if ctl[C_STATUS] != STATUS_CONVERGED:
        reason = "a non-finite residual" if ctl[C_STATUS] == STATUS_NONFINITE else f"{iterations} iterations"
        raise StaticsNotConverged(f"static equilibrium not reached after {reason} (largest residual/weight "
                                  f"{ctl[C_RESIDUAL]:.3g}, tolerance {tol_rel:g})", float(ctl[C_RESIDUAL]))
    return StaticsReport(iterations, float(ctl[C_RESIDUAL]), 0.0, n_dofs, "newton")
