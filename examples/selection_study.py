"""A small selection study from Python: which node selection and mode count of the target
rod reproduce its full-FE contact force, and the smallest model that reaches a target NCC,
against the a-priori estimate from the 1D theory. Nothing is written (a temporary directory
holds the cases); pass out_dir to keep them and resume.

    python examples/selection_study.py       # tests/data/tiny_impact.toml, 8 runs, ~1 min
"""

from __future__ import annotations

from pathlib import Path

import flexmvm as fm

TINY = Path(__file__).resolve().parents[1] / "tests" / "data" / "tiny_impact.toml"


def main(scenario: str | Path = TINY, target: float = 0.99, serial: bool = True) -> dict:
    sc = fm.load_scenario(scenario)
    study = fm.select(sc, "b2", layers=[1, 2], laps=[1, 2], modes=[7, 13], target=target,
                      serial=serial)
    for row in study.rows:
        print(f"{row['layers']}-{row['laps']} + {row['modes']:2d} modes ({row['dof']:3d} DOF): "
              f"NCC {row.get('ncc_force', float('nan')):.6f}")
    best = study.best
    estimate = fm.estimate_selection(sc, "b2", modes=[7, 13])
    if best is not None:
        print(f"smallest model reaching NCC >= {target}: {best['layers']}-{best['laps']} + "
              f"{best['modes']} modes ({best['dof']} DOF)")
    print(f"a-priori estimate: {estimate['layers']}-{estimate['laps']} + {estimate['modes']} "
          f"modes ({estimate['dof']} DOF)")
    return {"study": study, "best": best, "estimate": estimate}


if __name__ == "__main__":
    main()
