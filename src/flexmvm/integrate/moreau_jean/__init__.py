"""The Moreau-Jean theta scheme, the one integrator of the package, as its own package: the
scheme (scheme.py: the residual, the Newton loop and the step) and the modules only it uses:
per-body solves and their threads (body_solver, body_threads, dense_solve), the iteration
matrix and its relaxation (iteration_matrix, relaxation, newton_iterate, stall_report), the
products carried with the states (carried, w_images, residual_kernels), the constraint solves
(compliance, lcp, coulomb, velocity_projection, momentum_balance), the massless coordinates
(massless, massless_kernels), the non-rotating step (nonrotating) and the plastic bodies'
tangent (plastic_tangent). Outside code takes the integrator from here; the step contract it
fulfils (integrate.step), the driver and the run result live one level up."""

from flexmvm.integrate.moreau_jean.scheme import MoreauJeanIntegrator

__all__ = ["MoreauJeanIntegrator"]
