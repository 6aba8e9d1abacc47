"""What a run keeps at its output times: energies (kinetic, strain, gravity potential), linear
and angular momentum, frame states, elastic coordinates and rates, probes, contact and joint
forces (integrate.driver records one row per output; RunResult is made from the rows).

Fields (q and q_dot, per body: what displacements and stresses are made of) are the bulk of a
run's memory: 25,767 DOF at 1,001 outputs are 413 MB. With a field output rate
(TimeGrid.field_output_dt_s) a row keeps them only if it is a field row: the first output at
or after each multiple of field_dt_s from the start, and the last output (a row keeps them
until the next one is recorded, so the driver's finiteness check and the end of a run see
them)."""

from __future__ import annotations

import numpy as np

from flexmvm.constraints.drives import drive_torques
from flexmvm.integrate.run_result import FieldPrecision, RunResult, TimeGrid
from flexmvm.integrate.system import System


class OutputRecorder:
    def __init__(
        self,
        system: System,
        probes,
        n_out_max: int,
        n_joint_rows: int,
        grid: TimeGrid | None = None,
    ):
        """grid: the run's TimeGrid, for its field output rate and precision (None: fields
        at every output, float64)."""
        self.system, self.probes = system, list(probes)
        self.field_dt_s = None if grid is None else grid.field_output_dt_s
        self.field_precision = FieldPrecision.FLOAT64 if grid is None else grid.field_precision
        self._t0: float | None = None  # the time of row 0 [s]
        self._next_k = 0  # the next field time is t0 + _next_k field_dt_s
        self._last_is_field = True
        nb, npb = len(system.bodies), len(self.probes)
        self.rows: list[dict] = []
        self.n_joint_rows = n_joint_rows
        self.shape = (nb, npb)
        # the integrator's plastic bodies (integrate.plastic_bodies): their elastic energy is
        # 1/2 q^T k_hat q plus a correction; None: none
        self.plastic = None

    def record(self, t, states, force, jforce, carried=None, products=None):
        """carried(b, state) -> (L(q), L(q_dot)): the integrator's carried contractions;
        products(b, state) -> (k_hat q, M_qq q_dot), the same for the energies."""
        sysm = self.system
        rec = {"t": t, "force": force, "jforce": jforce}
        kin = strain = pot = 0.0
        p = np.zeros(3)
        h = np.zeros(3)
        pb = []
        for b, (body, st) in enumerate(zip(sysm.bodies, states)):
            Lq = carried(b, st)[0] if (carried is not None and body.nq) else None
            terms = body.inertia_terms(st.q, Lq)
            kq, mqq_v = products(b, st) if (products is not None and body.nq) else (None, None)
            kin += body.kinetic_energy(st.A, st.q, st.v, terms, mqq_v)
            strain += body.strain_energy(st.q, kq)
            pot -= float(sysm.gravity @ (body.inv.mass * st.r + st.A @ terms[0]))
            pb.append(body.linear_momentum(st.A, st.q, st.v, terms))
            p += pb[-1]
            h += body.angular_momentum(st.r, st.A, st.q, st.v, terms)
        if self.plastic is not None:
            strain += self.plastic.strain_energy_correction(states)
            rec["plastic"] = self.plastic.cell_fields()
        rec.update(kin=kin, strain=strain, pot=pot, p=p, h=h, pb=np.array(pb))
        rec["r"] = np.array([st.r for st in states])
        rec["A"] = np.array([st.A for st in states])
        rec["v"] = np.array([st.v[:6] for st in states])
        rec["q"] = [st.q.copy() for st in states]
        rec["qd"] = [st.v[6:].copy() for st in states]
        px, pv = [], []
        for pr in self.probes:
            body, st = sysm.bodies[pr.body], states[pr.body]
            if pr.nodes:  # a point inside an element: its nodes weighted by the shape functions
                nodes, w = np.asarray(pr.nodes), np.asarray(pr.weights)
                px.append(w @ body.node_positions(nodes, st.r, st.A, st.q))
                pv.append(w @ body.node_velocities(nodes, st.A, st.q, st.v))
                continue
            node = np.array([pr.node])
            px.append(body.node_positions(node, st.r, st.A, st.q)[0])
            pv.append(body.node_velocities(node, st.A, st.q, st.v)[0])
        rec["px"], rec["pv"] = np.array(px).reshape(-1, 3), np.array(pv).reshape(-1, 3)
        self._keep_fields(rec)
        self.rows.append(rec)

    def _keep_fields(self, rec: dict) -> None:
        """Drop q and q_dot of the previous row unless it is a field row; mark this one."""
        dt = self.field_dt_s
        if dt is None:
            return
        t = float(rec["t"])
        if self.rows and not self._last_is_field:
            self.rows[-1]["q"] = self.rows[-1]["qd"] = None
        if self._t0 is None:
            self._t0 = t
        # field time k: t0 + k dt, reached to round-off (outputs fall on whole ticks)
        k = int(np.floor((t - self._t0) / dt * (1 + 1e-9) + 1e-9))
        self._last_is_field = k >= self._next_k
        self._next_k = max(self._next_k, k + 1)

    def result(self, **extra) -> RunResult:
        R = self.rows
        nb = self.shape[0]
        kept = [k for k, r in enumerate(R) if r["q"] is not None]
        F = [R[k] for k in kept]
        jforce = np.array([r["jforce"] for r in R]).reshape(len(R), self.n_joint_rows)
        return RunResult(
            t=np.array([r["t"] for r in R]),
            body_names=[b.name for b in self.system.bodies],
            frame_r=np.array([r["r"] for r in R]),
            frame_v=np.array([r["v"] for r in R]),
            probe_names=[p.name for p in self.probes],
            probe_axes=[p.axis for p in self.probes],
            probe_x=np.array([r["px"] for r in R]),
            probe_v=np.array([r["pv"] for r in R]),
            contact_force=np.array([r["force"] for r in R]),
            joint_force=jforce,
            drive_torque=drive_torques(self.system.joints, jforce),
            kinetic=np.array([r["kin"] for r in R]),
            strain=np.array([r["strain"] for r in R]),
            potential=np.array([r["pot"] for r in R]),
            momentum=np.array([r["p"] for r in R]),
            angular_momentum=np.array([r["h"] for r in R]),
            q=[_stacked([r["q"][b] for r in F]) for b in range(nb)],
            q_dot=[_stacked([r["qd"][b] for r in F]) for b in range(nb)],
            frame_A=np.array([r["A"] for r in R]),
            body_momentum=np.array([r["pb"] for r in R]),
            field_index=None if self.field_dt_s is None else np.array(kept, dtype=int),
            field_precision=self.field_precision,
            **extra,
        )


def _stacked(rows: list[np.ndarray]) -> np.ndarray:
    """The rows (n_out, nq); rows of different lengths (a moving region's windows hold
    different node counts on an unstructured path) padded with NaN to the longest."""
    if len({r.shape for r in rows}) <= 1:
        return np.array(rows)
    out = np.full((len(rows), max(r.size for r in rows)), np.nan)
    for i, r in enumerate(rows):
        out[i, : r.size] = r
    return out
