"""A run that blew up fails instead of reporting success.

A point-to-surface pair holds the slave nodes out of the master facets, not the master's nodes
out of the slave's: a master edge or corner between two flexible bodies can go through the
slave surface unopposed (a link's tip edge struck a cantilever 3.4 mm deep, 97 kN, the total
energy +1.2e6 %, and the run ended "completed"). The penetration measure (contact.penetration)
sees both directions, and the energy ledger the energy no input put in; a run whose numbers
pass either bound below is a failure (status "failed", exit 2, its histories kept), named by
the pair, the node, the time and the pair that would have held it.

The penetration measure reaches only the pair's search radius beyond the surface (plus the
facets' largest displacement, contact.penetration): a node that went through the other body
reads that deep, then nothing. A coarse link's edge struck a coarse cantilever at 5 m/s with the
one pair that holds the cantilever's nodes out of the link (tests/test_two_pass.py): the edge
went straight through, the measure read 0.2 mm (the default search radius 2e-4 m, 3 % of the
cantilever's 6 mm thickness) and no contact force at all; the run passed. A node as deep as
REACH_FAIL_SHARE of its pair's search radius therefore fails the run too.

The bounds are far from any healthy run: the stored validation and study runs penetrate at
most 5.6 um (a soft PA6 rod, 20 mm across; 1/18 of REACH_FAIL_SHARE x 2e-4 m) and gain at
most ENERGY_GAIN_WARN (0.5 %) of their energy (runs/guard.py warns there).
"""

from __future__ import annotations

import numpy as np

#: Total energy risen beyond the inputs' work by more than this share of its start (or of the
#: largest input work, runs.run.energy_gain): the run failed
ENERGY_GAIN_FAIL = 0.1
#: A node deeper in the other body's contact surface than this share of that body's thinnest
#: extent (the smallest side of its bounding box in its own frame): the run failed
PENETRATION_FAIL_SHARE = 0.1
#: A node deeper than this share of the search radius of its pairs (the penetration measure's
#: reach, module doc): it may have gone through unseen, the run failed
REACH_FAIL_SHARE = 0.5


def thinnest_extent_m(body) -> float:
    """The smallest side [m] of the bounding box of body's undeformed nodes X (n, 3)."""
    X = np.asarray(body.X)
    return float(np.min(X.max(axis=0) - X.min(axis=0)))


def _pairs_between(built, a: str, b: str) -> list[tuple[str, str, str, float]]:
    """(name, slave body, master body, search radius [m]) of the contact pairs between bodies
    a and b."""
    names = [i.name for i in built.info]
    out = []
    for c in built.system.contacts:
        s, m = c.slave, c.master
        if {names[s], names[m]} == {a, b}:
            out.append((c.name, names[s], names[m], float(c.search_radius)))
    return out


def _penetration_line(summary: dict, built) -> str | None:
    at = summary.get("max_penetration_at")
    depth = summary.get("max_penetration_m") or 0.0
    if not at:
        return None
    bodies = {i.name: k for k, i in enumerate(built.info)}
    extent = thinnest_extent_m(built.system.bodies[bodies[at["against"]]])
    pairs = _pairs_between(built, at["body"], at["against"])
    radius = min((p[3] for p in pairs), default=np.inf)
    if depth <= min(PENETRATION_FAIL_SHARE * extent, REACH_FAIL_SHARE * radius):
        return None
    if depth > PENETRATION_FAIL_SHARE * extent:
        bound = (
            f"more than {PENETRATION_FAIL_SHARE:.0%} of that body's thinnest extent, {extent:.3g} m"
        )
    else:
        bound = (
            f"at least: the measure reaches {radius:.3g} m, the pair's search radius, "
            "beyond the surface; it may have gone through"
        )
    line = (
        f"the contact failed: node {at['node']} of body {at['body']!r} went {depth:.3g} m into "
        f"the surface of body {at['against']!r} at t = {at['t_s']:.6g} s ({bound})"
    )
    if pairs and all(p[2] == at["body"] for p in pairs):
        named = ", ".join(p[0] for p in pairs)
        line += (
            f": pair {named} holds {at['against']!r}'s nodes out of {at['body']!r}'s facets, not "
            f"this direction; add the reverse pair (slave {at['body']!r}, master "
            f"{at['against']!r}), or set two_pass = true on that contact, so that both surfaces "
            "are checked"
        )
    elif pairs:
        line += f" through pair {', '.join(p[0] for p in pairs)}: a finer step or mesh there"
    return line


def blowup_failure(summary: dict, built) -> str | None:
    """The one-line reason a completed run failed (module doc), or None: a penetration beyond
    PENETRATION_FAIL_SHARE of the penetrated body's thinnest extent or REACH_FAIL_SHARE of its
    pairs' search radius, or an energy gain beyond ENERGY_GAIN_FAIL."""
    line = _penetration_line(summary, built)
    if line is not None:
        return line
    gain = summary.get("energy_gain_rel_max")
    if gain is not None and gain > ENERGY_GAIN_FAIL:
        return (
            f"the total energy rose by {100 * gain:.3g} % of its start beyond the work of the "
            f"loads and drives (more than {ENERGY_GAIN_FAIL:.0%}): the contact or the scheme "
            "put energy in; the histories are not a solution (contact pairs one-sided between "
            "flexible bodies, a step too long for the contact, chatter)"
        )
    return None
