"""Contact law x mass redistribution on the short seed case (issue 14 part 3).

    python benchmarks/contact_law_study.py MODEL THETA LAW REDIS [DT_US] [OUT.json] [SCENARIO]

THETA: a number, or tau=T (T in us) for theta = 1/2 + h / (4 T) (time.hf_damping_time_s);

MODEL: shipped (the scenario's models: on the short case b1 full FE, b2 MVM 1-3 + 37), a
model kind for every body (full, mvm, mvm-seed, ...) or one per body, "b1=mvm,b2=mvm:1-5"
(kind, optionally :selection); LAW: velocity or position; REDIS: 0 or 1
(redistribute_mass); SCENARIO: default scenarios/rod_impact_short.toml (the seed case:
scenarios/rod_impact.toml). Writes a JSON line of measures:
- energy: (E - E0) / E0 at the end (t_end, after separation) and the largest |E - E0| / E0;
- ncc / peak_err: force history against `flexmvm theory` (runs.compare.compare_runs);
- pen: the run's max_penetration_m (both directions, after every step);
- ring: the mean over the steps of the contact interval (k-1, k, k+1 all at h) and over the
  contact nodes (slave nodes that carried an impulse at any step, and the nodes of their
  master facets) of |u(k+1) - 2 u(k) + u(k-1)| / v0, u the node's global x velocity at the
  step ends (the impact axis), v0 = 0.21 m/s; ring_slave / ring_master apart, ring_p99: the
  99th percentile of that quantity;
- ringx: the same of the steps' mean velocities (x(k) - x(k-1)) / h (= v_m, what moves the
  nodes; the end velocity v+ of a massless node is no state: it carries no kinetic energy);
- ringx_window_slave / ringx_window_master: ringx over fixed windows of 0.5, 1 and 2 us
  (those at least h) instead of steps: the same quantity at every step h that divides the
  window, so runs at h, h / 2, h / 4 tell the model's own motion on that time scale (it
  converges with h) from an alternation the step makes (it does not);
- ring_face_free / ringx_face_free: both measures on the slave face's nodes that never carried
  an impulse (the control: the same face's elastic response without contact);
- force_ring: the same second difference of the per-step contact force impulse/h, mean over
  the contact interval, relative to the peak force.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

import flexmvm as fm
from flexmvm.assembly.build import build_scenario
from flexmvm.contact.nodes import ContactNodes
from flexmvm.integrate import driver
from flexmvm.integrate.moreau_jean import MoreauJeanIntegrator
from flexmvm.runs.compare import compare_runs
from flexmvm.theory.scenario import theory_histories

SHORT = "scenarios/rod_impact_short.toml"


def scenario(model: str, theta: float, law: str, redis: bool, dt: float | None, path: str = SHORT):
    sc = fm.load_scenario(path)
    if model != "shipped" and "=" not in model:
        sc = sc.with_kind(model)
    data = sc.model_dump(mode="json")
    if "=" in model:  # per body: "b1=mvm,b2=mvm:1-5" (kind, optionally :selection)
        for item in model.split(","):
            name, spec = item.split("=")
            kind, _, selection = spec.partition(":")
            body = next(b for b in data["bodies"] if b["name"] == name)
            body["model"]["kind"] = kind
            if selection:
                body["model"]["selection"] = selection
    data["contacts"][0]["law"] = law
    data["contacts"][0]["redistribute_mass"] = bool(redis)
    if isinstance(theta, str):  # "tau=12.5": theta = 1/2 + h / (4 tau), tau [us]
        data["time"].pop("theta", None)
        data["time"]["hf_damping_time_s"] = float(theta.partition("=")[2]) * 1e-6
        sc = fm.scenario_from_dict(data)
        return sc.with_time(**({"dt_s": dt} if dt else {}))
    sc = fm.scenario_from_dict(data)
    return sc.with_time(theta=theta, **({"dt_s": dt} if dt else {}))


def main(model, theta, law, redis, dt_us=None, out=None, path=SHORT):
    theta = theta if str(theta).startswith("tau=") else float(theta)
    redis = bool(int(redis))
    dt = float(dt_us) * 1e-6 if dt_us else None
    sc = scenario(model, theta, law, redis, dt, path)
    built = build_scenario(sc)
    system = built.system
    prov = system.contacts[0]
    s_nodes = ContactNodes(system.bodies[prov.slave], prov.slave_nodes)
    m_nodes = ContactNodes(system.bodies[prov.master], prov.master_nodes)
    rec = {
        "t": [],
        "h": [],
        "us": [],
        "um": [],
        "xs": [],
        "xm": [],
        "imp": [],
        "n_on": [],
        "n_rows": [],
    }
    touched_s, touched_m = set(), set()

    class Recording(MoreauJeanIntegrator):
        def step(self, t, states, h):
            res = super().step(t, states, h)
            s_nodes.update(res.states[prov.slave])
            m_nodes.update(res.states[prov.master])
            rec["t"].append(t + h)
            rec["h"].append(h)
            rec["us"].append(s_nodes.xd[:, 0].copy())
            rec["um"].append(m_nodes.xd[:, 0].copy())
            rec["xs"].append(s_nodes.x[:, 0].copy())
            rec["xm"].append(m_nodes.x[:, 0].copy())
            lam = res.contact_impulses
            rec["imp"].append(float(res.contact.normal_impulse(lam)))
            rec["n_rows"].append(res.contact.rows.m)
            rec["n_on"].append(int((lam > 0).sum()))
            last = prov._last[0]  # (slave index, master facet nodes (local), weights, normal)
            if last is not None and lam.size:
                point, nodes, weights = last[0], last[1], last[2]
                for j in np.nonzero(lam[: len(point)] > 0)[0]:
                    touched_s.add(int(point[j]))
                    touched_m.update(int(n) for n, w in zip(nodes[j], weights[j]) if w != 0.0)
            return res

    driver.MoreauJeanIntegrator = Recording
    w0 = time.perf_counter()
    run = driver.simulate(system, built.states, built.grid, built.probes)
    wall = time.perf_counter() - w0
    v0 = 0.21
    E = run.total_energy
    t_f, f, probes = run.curves()
    tt, ft, pt, _ = theory_histories(sc)
    cmp_ = compare_runs(tt, ft, pt, t_f, f, probes)
    t_s, h_s = np.array(rec["t"]), np.array(rec["h"])
    F = np.array(rec["imp"]) / h_s
    on = np.nonzero(F > 0)[0]
    k0, k1 = on[0], on[-1]
    hc = h_s[k0]
    ks = np.arange(max(k0, 1), k1)  # k-1, k, k+1 inside [k0-1, k1+1]
    ks = ks[(h_s[ks - 1] == hc) & (h_s[ks] == hc) & (h_s[ks + 1] == hc)]

    def ring(key, nodes):
        U = np.array(rec[key])[:, sorted(nodes)]
        if key.startswith("x"):  # the step's mean velocity (x(k) - x(k-1)) / h: h v_m
            U = np.vstack([U[:1] * np.nan, np.diff(U, axis=0) / h_s[1:, None]])
        d2 = np.abs(U[ks + 1] - 2 * U[ks] + U[ks - 1]) / v0
        return float(np.nanmean(d2)), float(np.nanpercentile(d2, 99))

    rs, rs99 = ring("us", touched_s)
    rm, rm99 = ring("um", touched_m)
    ps, ps99 = ring("xs", touched_s)
    pm, pm99 = ring("xm", touched_m)
    free = set(range(len(prov.slave_nodes))) - touched_s  # the slave face outside the patch
    pf, _ = ring("xs", free)
    vf, _ = ring("us", free)
    d2f = np.abs(F[ks + 1] - 2 * F[ks] + F[ks - 1])

    def ring_windows(key, nodes, w):
        """ringx over fixed windows of w [s] instead of steps: the mean velocities
        (x(t_j) - x(t_j - w)) / w at step ends t_j = j w, second differences over the contact
        interval; the same quantity at every h that divides w (module doc)."""
        X = np.array(rec[key])[:, sorted(nodes)]
        j = np.rint(t_s / w)
        at = np.nonzero(np.abs(t_s - j * w) < 1e-9 * w)[0]
        at = at[np.concatenate([[True], np.diff(j[at]) > 0])]
        jj, tw = j[at], t_s[at]
        V = np.diff(X[at], axis=0) / w
        ok = np.diff(jj) == 1  # consecutive windows only
        d2 = np.abs(V[2:] - 2 * V[1:-1] + V[:-2]) / v0
        sel = ok[2:] & ok[1:-1] & ok[:-2] & (tw[2:-1] >= t_s[k0]) & (tw[2:-1] <= t_s[k1])
        return float(d2[sel].mean()) if sel.any() else float("nan")

    out_d = {
        "scenario": path,
        "model": model,
        "theta": theta,
        "theta_used": built.grid.theta,
        "law": law,
        "redis": redis,
        "dt_us": hc * 1e6,
        "energy_end": float((E[-1] - E[0]) / E[0]),
        "energy_max": float(np.abs(E - E[0]).max() / E[0]),
        "ncc": cmp_.get("ncc_force"),
        "peak_err": cmp_.get("peak_err"),
        "peak_N": float(F.max()),
        "peak_out_N": float(np.max(f)),
        "pen_um": run.max_penetration_m * 1e6,
        "pen_dirs_um": {k: v * 1e6 for k, v in run.max_penetration_by_direction_m.items()},
        "ring_slave": rs,
        "ring_slave_p99": rs99,
        "ring_master": rm,
        "ring_master_p99": rm99,
        "ringx_slave": ps,
        "ringx_slave_p99": ps99,
        "ringx_master": pm,
        "ringx_master_p99": pm99,
        "ringx_face_free": pf,
        "ring_face_free": vf,
        "force_ring": float(d2f.mean() / F.max()),
        "ringx_window_slave": {
            f"{w * 1e6:g}us": ring_windows("xs", touched_s, w)
            for w in (0.5e-6, 1e-6, 2e-6)
            if w >= hc * (1 - 1e-9)
        },
        "ringx_window_master": {
            f"{w * 1e6:g}us": ring_windows("xm", touched_m, w)
            for w in (0.5e-6, 1e-6, 2e-6)
            if w >= hc * (1 - 1e-9)
        },
        "n_touched": [len(touched_s), len(touched_m)],
        "contact_us": [float(t_s[k0] * 1e6), float(t_s[k1] * 1e6)],
        "ncc_b2_free_end": cmp_.get("ncc_b2_free_end"),
        "wall_s": wall,
        "steps": run.n_steps,
        "lcp_res": run.lcp_residual_max,
    }
    line = json.dumps(out_d)
    print(line)
    if out:
        with open(out, "a") as fh:
            fh.write(line + "\n")
        np.savez(
            out.replace(".json", "")
            + f"_{Path(path).stem}_{model}_{theta}_{law}_{int(redis)}_{hc * 1e6:g}.npz",
            t=t_f,
            f=f,
            t_step=t_s,
            F_step=F,
            E=E,
            t_E=run.t,
            xs=np.array(rec["xs"])[:, sorted(touched_s)],
            us=np.array(rec["us"])[:, sorted(touched_s)],
            n_on=np.array(rec["n_on"]),
            n_rows=np.array(rec["n_rows"]),
        )
    return out_d, np.asarray(t_f), np.asarray(f)


if __name__ == "__main__":
    main(*sys.argv[1:])
