"""Time integration: the Moreau-Jean theta scheme (moreau_jean/scheme.py), its fast paths and
solvers, and the time loop (driver.py)."""

#: theta of the Moreau-Jean scheme when none is given, here only (scenarios, TimeGrid and the
#: integrator read it): 0.55 damps the contact nodes' step-to-step ringing at a first-order
#: cost (moreau_jean/scheme.py); 1/2 is the second-order, energy-conserving implicit midpoint rule.
#: A scenario with time.hf_damping_time_s tau (the seed scenarios) takes neither: theta(h) =
#: 1/2 + h / (4 tau) up to the contact step dt_s, 1/2 + dt_s^2 / (4 tau h) above it, second
#: order (integrate.theta).
DEFAULT_THETA = 0.55
