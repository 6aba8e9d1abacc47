"""Rod impact built in Python: the seed case (brass rod with a hemispherical end at 0.21 m/s
onto an aluminium rod) as a scenario dict, run with an MVM aluminium rod and with it full FE,
compared with each other and with the 1D wave-Hertz theory.

    python examples/rod_impact.py            # 0.1 m rods, 0.25 ms (about 30 s)
"""

from __future__ import annotations

import flexmvm as fm


def scenario(length_m: float = 0.1, t_end_s: float = 2.5e-4) -> fm.Scenario:
    """The seed case on rods of length_m [m] (docs/scenario_format.md for every key)."""
    rod = {"length_m": length_m, "radius_m": 0.01}
    return fm.scenario_from_dict({
        "name": "rod_impact_python",
        "time": {"t_end_s": t_end_s, "dt_s": 0.5e-6, "dt_max_s": 2e-6, "output_dt_s": 2e-6},
        "bodies": [
            {"name": "b1", "material": "brass",
             "rod": rod | {"end_a": "hemisphere"},
             "placement": {"rotation": {"axis": [0, 0, 1], "angle_deg": 180.0},
                           "velocity_mps": [0.21, 0.0, 0.0]}},
            {"name": "b2", "material": "aluminium", "rod": rod},
        ],
        "contacts": [{"slave": "b2.end_a", "master": "b1.end_a"}],
        "probes": [{"name": "b2_impact_end", "body": "b2", "node_set": "end_a_centre"},
                   {"name": "b2_free_end", "body": "b2", "node_set": "end_b_centre"}],
    }, source="examples/rod_impact.py")


def main(t_end_s: float = 2.5e-4, modes: int = 37) -> dict:
    sc = scenario(t_end_s=t_end_s)
    mvm = fm.run(sc.with_model("b2", fm.mvm("1-3", modes)))
    full = fm.run(sc)  # every body full FE: the scenario's default model
    theory = fm.theory_histories(sc)[:3]
    out = {"mvm_vs_full": fm.compare(mvm, full), "full_vs_theory": fm.compare(full, theory),
           "dof_b2": mvm.dof("b2"), "mvm": mvm, "full": full}
    print(f"b2 MVM 1-3 + {modes} modes: {out['dof_b2']} DOF; force NCC against full FE "
          f"{out['mvm_vs_full'].ncc_force:.6f}, full FE against the 1D theory "
          f"{out['full_vs_theory'].ncc_force:.6f}")
    print(f"peak force {full.contact_force.max():.1f} N (full FE), "
          f"{mvm.contact_force.max():.1f} N (MVM); free-end velocity at the end "
          f"{mvm.probe('b2_free_end').v[-1, 0]:.4f} m/s")
    return out


if __name__ == "__main__":
    main()
