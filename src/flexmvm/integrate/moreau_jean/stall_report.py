"""Where a step's iteration stalled, in one line, for the error of a step that does not
converge (moreau_jean/scheme.py)."""

from __future__ import annotations

import numpy as np

from flexmvm.constraints.contact import ContactRows


def stall_report(bodies, res, scales, rtol: float, crows: ContactRows, lam_c, n_j: int) -> str:
    """The body and row of the largest relative residual (frame translation / rotation, or
    elastic coordinate; for a nodal basis the mesh node and direction), and the contact pairs
    of the step's rows (contact, slave node, master facet) with their impulses. res, scales:
    per body its residual (constraint impulses included) and momentum scale."""
    worst = max(range(len(res)), key=lambda b: float(np.abs(res[b]).max()) / max(scales[b], 1e-300))
    body, r = bodies[worst], res[worst]
    i = int(np.argmax(np.abs(r)))
    rel = float(abs(r[i])) / max(scales[worst], 1e-300)
    if i < 3:
        row = f"frame translation {'xyz'[i]}"
    elif i < 6:
        row = f"frame rotation {'xyz'[i - 3]}"
    else:
        row = f"elastic coordinate {i - 6}"
        node = body.node_of_coordinate(i - 6)
        if node is not None:
            row += f" (node {node[0]} {'xyz'[node[1]]})"
    text = f"largest residual {rel:.2e} (of rtol {rtol:.0e}) in body {body.name!r}, {row}"
    m = crows.rows.m
    if m:
        keys = crows.keys
        on = [k for k, x in zip(keys, lam_c) if x > 0.0]
        shown = ", ".join(
            f"{k[0]} node {k[1]} on facet {k[2]}" if len(k) >= 3 else str(k)
            for k in (on or keys)[:3]
        )
        text += (
            f"; {m} contact row(s), {len(on)} carrying impulse ({shown}"
            + (" ..." if len(on or keys) > 3 else "")
            + ")"
        )
    if n_j:
        text += f"; {n_j} joint row(s)"
    return text
