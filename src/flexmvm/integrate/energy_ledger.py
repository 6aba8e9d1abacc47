"""The energy ledger of a run: the work of everything that acts on the bodies, summed over the
accepted steps, and the balance that must close against the energies at the outputs.

Per step from t over h, with v- and v+ the velocities at t and t + h, dv = v+ - v-,
v_m = theta v+ + (1 - theta) v- and x_m the step's midpoint (integrate.moreau_jean):

- applied loads (flexmvm.loads): W += h F_load(x_m, v_m, t + theta h) . v_m, per load; a
  spring-damper's damper part c l_dot^2 h is also kept (so its elastic work can be set
  against its stored energy);
- joints: W += lambda_J . (Phi_v(x_m) v_m), per joint (each entry of System.joints): zero up
  to the scheme's error for an ideal scleronomic joint, the input work of a rheonomic one (a
  prescribed motion, a drive): generic over every Joint (evaluate's rows);
- contacts: W += lambda_C . (Phi_C v_m) (the step's contact rows);
- damping: D += h v_m^T c_hat v_m over the elastic rows;
- a spinning body's geometric stiffening (bodies.stiffening): W += h (-s K_G q_m) . q_dot_m,
  counted as the work of an applied force: its stiffness s(t) K_G changes with the spin, so
  1/2 s q^T K_G q is not a stored energy of the body (the strain energy is 1/2 q^T k_hat q);
- the scheme's numerical dissipation at theta > 1/2:
  D += (theta - 1/2) (dv^T M dv + dq^T k_hat dq), dq = q(t + h) - q(t);
- plastic bodies (integrate.plastic_bodies): P = sum over the steps of the work psi^T c(q_m) . dq
  of their force correction, less (elastic energy - 1/2 q^T k_hat q) at the output, so that E
  holds their elastic energy: P is their plastic work (dissipation and stored hardening) to
  the scheme's order, and the balance closes with it as without plasticity.

The last follows from the step's equations (Acary 2016, "Energy conservation and dissipation
properties of time-integration methods for nonsmooth elastodynamics with contact", ZAMM 96(5),
eq. 37 for the Moreau-Jean theta scheme): with M constant, 1/2 (v+ + v-) = v_m - (theta - 1/2)
dv, so dT = v_m^T M dv - (theta - 1/2) dv^T M dv = v_m^T (h F + Phi^T lambda) - (theta - 1/2)
dv^T M dv; with q_m = q + theta dq, dU = 1/2 (q+ + q-)^T K dq = q_m^T K dq - (theta - 1/2)
dq^T K dq, and -q_m^T K dq is the elastic force's work h (-K q_m) . q_dot_m. Hence

    E(t) - E(0) - W_loads - W_joints - W_contact + D_damping + D_numerical (+ P) = residual

with E = kinetic + strain + gravity potential (integrate.recorder.OutputRecorder), which closes to the Newton
tolerance for bodies whose mass matrix is constant over the step (frames that do not rotate)
and to the scheme's order otherwise (M(x) and the frame's rotation make the step's kinetic
energy identity approximate: O(h^2) per unit time at theta = 1/2). dv^T M dv uses the mass
matrix at the step's end (x_m differs by O(h): a relative change O(h) of a term already
O(theta - 1/2)). An integrator whose ``theta_rule`` is None is taken as theta = 1/2.

What the ledger asks of a load is declared (Load; a spring's stored energy and dissipation:
StoringLoad), and of an integrator by integrate.step.Integrator: nothing is probed for.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from flexmvm.bodies.momentum import increment_norm
from flexmvm.bodies.rotation import cross3
from flexmvm.integrate.row_products import body_impulse, flat_product
from flexmvm.integrate.system import Load, StoringLoad
from flexmvm.loads.applied import midpoint_states, start_run

if TYPE_CHECKING:
    from flexmvm.integrate.plastic_bodies import PlasticBodies
    from flexmvm.integrate.state import BodyState
    from flexmvm.integrate.step import CarriedStates, Integrator
    from flexmvm.integrate.system import System


def load_label(k: int, load: Load) -> str:
    """'loads[k] <Kind>' or its name: the key of a load's work."""
    return load.name if load.name else f"loads[{k}] {type(load).__name__}"


def joint_label(k: int, joint) -> str:
    """'joints[k] <Kind>' (the index in System.joints): the key of a joint's work."""
    return f"joints[{k}] {type(joint).__name__}"


@dataclass
class EnergyLedgerHistory:
    """Cumulative works and dissipations [J] at the output times (n_out,) or (n_out, k):
    loads (per load, labels ``load_names``), of which their dampers dissipated
    ``load_damping``, joints (per joint, ``joint_names``), contact, damping of the bodies
    (c_hat), the scheme's numerical dissipation; ``load_energy`` the energy stored in the
    springs (per load, 0 for loads without)."""

    load_names: list[str]
    joint_names: list[str]
    loads: np.ndarray
    load_damping: np.ndarray
    load_energy: np.ndarray
    joints: np.ndarray
    contact: np.ndarray
    damping: np.ndarray
    numerical: np.ndarray
    stiffening: np.ndarray | None = None  # work of the geometric stiffening forces
    plastic: np.ndarray | None = None  # plastic work of the plastic bodies (module doc)

    def inputs(self) -> np.ndarray:
        """The work put in from outside the bodies' contact (n_out,) [J]: applied loads,
        joints (drives, prescribed motions) and a spinning body's stiffening forces."""
        works = self.loads.sum(axis=1) + self.joints.sum(axis=1)
        return works if self.stiffening is None else works + self.stiffening

    def residual(self, total_energy: np.ndarray) -> np.ndarray:
        """E(t) - E(0) - works + dissipations (n_out,) [J] (module doc)."""
        E = np.asarray(total_energy)[: len(self.contact)]
        works = self.inputs() + self.contact
        dissipated = self.damping + self.numerical
        if self.plastic is not None:
            dissipated = dissipated + self.plastic
        return E - E[0] - works + dissipated


@dataclass
class EnergyLedger:
    """Sums the works of an accepted step (``add``) and keeps them at each output
    (``record``); ``history`` gives them as arrays. ``carried(b, state)`` -> (L(q), L(q_dot)):
    the integrator's carried contractions (the mass matrix of a full-FE body without a pass
    over its nodes)."""

    system: System
    # (b, state) -> (L(q), L(q_dot)): the integrator's carried contractions, or None
    carried: Callable[[int, BodyState], tuple[np.ndarray, np.ndarray]] | None = None
    # the integrator's carried state (integrate.step.CarriedStates), whose k_hat q and M_qq
    # q_dot of a step's end give the dissipation's products for free; None: computed
    fresh: CarriedStates | None = None
    # the integrator's plastic bodies (integrate.plastic_bodies.PlasticBodies); None: none
    plastic: PlasticBodies | None = None
    w_loads: np.ndarray = field(init=False)
    d_loads: np.ndarray = field(init=False)
    w_joints: np.ndarray = field(init=False)
    sums: np.ndarray = field(init=False)  # contact, damping, numerical, stiffening
    rows: list = field(init=False)

    def __post_init__(self) -> None:
        start_run(self.system.loads)  # made once per run, before its first step (driver)
        self.w_loads = np.zeros(len(self.system.loads))
        self.d_loads = np.zeros(len(self.system.loads))
        self.w_joints = np.zeros(len(self.system.joints))
        self.sums = np.zeros(5)  # ... and the plastic bodies' correction work
        # per load: stores energy (StoringLoad), asked once per run
        self._storing: list[StoringLoad | None] = [
            load if isinstance(load, StoringLoad) else None for load in self.system.loads
        ]
        self.rows = []
        self._ends: dict = {}  # body -> (q, v, k_hat q, M_qq q_dot) of the last step's end

    def add(self, step) -> None:
        """One accepted step (driver.AcceptedStep: t_s, h_s, theta, start states, result)."""
        sysm, bodies = self.system, self.system.bodies
        t, h, theta, start, result = step.t_s, step.h_s, step.theta, step.start, step.result
        end = result.states
        v_plus = [st.v for st in end]
        mids = midpoint_states(start, v_plus, h, theta)
        vms = [m.v for m in mids]
        t_m = t + theta * h
        for k, load in enumerate(sysm.loads):
            for b, f in load.forces(bodies, mids, t_m).items():
                self.w_loads[k] += h * float(f @ vms[b])
            storing = self._storing[k]
            if storing is not None:
                self.d_loads[k] += h * storing.dissipation_rate(bodies, mids)
        lam_j, offset = result.joint_impulses, 0
        for k, joint in enumerate(sysm.joints):
            n = joint.n_rows
            if n and lam_j.size:
                _, rows = joint.evaluate(bodies, mids, t + 0.5 * h)
                self.w_joints[k] += _rows_work(rows, lam_j[offset : offset + n], bodies, vms)
            offset += n
        self.sums[0] += _rows_work(result.contact.rows, result.contact_impulses, bodies, vms)
        for body, vm in zip(bodies, vms):
            if body.c_hat is not None and body.nq:
                self.sums[1] += h * float(vm[6:] @ flat_product(body.c_hat, vm[6:]))
        for b, body in enumerate(bodies):
            if body.stiffening is not None and body.nq:  # the residual's -s K_G q_m
                f = body.stiffening.force(vms[b][3:6], mids[b].q)
                self.sums[3] -= h * float(f @ vms[b][6:])
        if theta != 0.5:
            self.sums[2] += (theta - 0.5) * self._increment_norms(start, end)
        self.sums[4] += result.plastic_work

    def _increment_norms(self, start, end) -> float:
        """sum over bodies of dv^T M dv + dq^T k_hat dq, M at the step's end (module doc):
        one product with M_qq and one with k_hat per body; the frame's rotational terms only
        when omega changed, from the integrator's carried contractions of the end state (the
        integrator's own, made by its step: no pass over the nodes). With those carried in
        the dense form, a body's sum is one compiled call (bodies.momentum.increment_norm)."""
        total = 0.0
        for b, (body, s0, s1) in enumerate(zip(self.system.bodies, start, end)):
            dv, dq = s1.v - s0.v, s1.q - s0.q
            if not body.nq:
                total += float(dv @ body.mass_times(s1.A, s1.q, dv))
                continue
            dqd = dv[6:]
            k_dq, mqq_dqd = self._products(b, body, s0, s1, dq, dqd)
            c1 = self.fresh.of_state(b, s1) if self.fresh is not None else None
            if c1 is not None and c1.Lq.ndim == 3:  # the whole sum in one compiled call
                inv = body.inv
                total += increment_norm(
                    s1.A, s1.q, c1.Lq, inv.mass, inv.S0, inv.S1, inv.G0, body.G1_array,
                    dv, mqq_dqd, dq, k_dq,
                )  # fmt: skip
                continue
            total += float(dq @ k_dq) + float(dqd @ mqq_dqd)
            coupling = s1.A @ (body.inv.S1 @ dqd)  # A S1 dq_dot, the translation-elastic part
            total += body.inv.mass * float(dv[:3] @ dv[:3]) + 2.0 * float(dv[:3] @ coupling)
            if np.any(dv[3:6]):
                Lq = self.carried(b, s1)[0] if self.carried is not None else None
                S, J, M_wq, _ = body.inertia_terms(s1.q, Lq)
                dw = dv[3:6]
                total += float(dw @ (J @ dw)) + 2.0 * float(dw @ (M_wq @ dqd))
                total += 2.0 * float(dv[:3] @ (s1.A @ cross3(dw, S)))
        return total

    def _products(self, b, body, s0, s1, dq, dqd) -> tuple[np.ndarray, np.ndarray]:
        """(k_hat dq, M_qq dq_dot): differences of the carried k_hat q and M_qq q_dot of the
        step's two ends when the integrator carried both (its Newton step:
        integrate.moreau_jean.carried, Kq+ = Kq- + h k_hat q_dot_m), else one product each."""
        c1 = self.fresh.of_state(b, s1) if self.fresh is not None else None
        c0 = self._ends.get(b)
        self._ends[b] = None if c1 is None else (s1.q, s1.v, c1.Kq, c1.Mqd)
        if c1 is not None and c0 is not None and c0[0] is s0.q and c0[1] is s0.v:
            return c1.Kq - c0[2], c1.Mqd - c0[3]
        return flat_product(body.k_hat, dq), flat_product(body.inv.M_qq, dqd)

    def record(self, states) -> None:
        """The sums so far, and the springs' stored energy at states: one output."""
        bodies = self.system.bodies
        stored = [
            storing.energy(bodies, states) if storing is not None else 0.0
            for storing in self._storing
        ]
        sums = self.sums.copy()
        if self.plastic is not None:
            sums[4] -= self.plastic.strain_energy_correction(states)
        self.rows.append(
            (self.w_loads.copy(), self.d_loads.copy(), np.array(stored), self.w_joints.copy())
            + tuple(sums)
        )

    def history(self, n_out: int) -> EnergyLedgerHistory:
        """The first n_out outputs as arrays."""
        rows = self.rows[:n_out]
        n_l, n_j = len(self.system.loads), len(self.system.joints)

        def col(i, width=None):
            if width is None:
                return np.array([r[i] for r in rows], dtype=float)
            return np.array([r[i] for r in rows], dtype=float).reshape(len(rows), width)

        return EnergyLedgerHistory(
            [load_label(k, x) for k, x in enumerate(self.system.loads)],
            [joint_label(k, j) for k, j in enumerate(self.system.joints)],
            col(0, n_l),
            col(1, n_l),
            col(2, n_l),
            col(3, n_j),
            col(4),
            col(5),
            col(6),
            col(7) if any(b.stiffening is not None for b in self.system.bodies) else None,
            col(8) if self.plastic is not None else None,
        )


def step_theta(integrator: Integrator, h: float) -> float:
    """theta of the integrator's step of size h [s] (its theta_rule; 1/2 without one)."""
    rule = integrator.theta_rule
    return 0.5 if rule is None else float(rule.at(h))


def _rows_work(rows, lam, bodies, vms) -> float:
    """lambda . (Phi v_m) [J] of constraint rows with impulses lam [N s]."""
    if not rows.m or not lam.size:
        return 0.0
    return sum(float(body_impulse(rows, b, bodies[b], lam) @ vms[b]) for b in rows.blocks)
