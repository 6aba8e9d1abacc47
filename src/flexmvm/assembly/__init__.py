"""Assembly: a System, its initial states, probes and time grid from a validated Scenario
(build.py), through the setup cache that computes meshes, FE models, bases and body parts once
(build_cache.py; the disk store is flexmvm.setup_cache). The parts of a build, one module per
job: supports and reference conditions (supports.py, body_reference.py), drives and joints
(drive_build.py), loads (load_build.py), mesh lookups (mesh_lookup.py), cache keys of a body's
mesh (cache_keys.py), the cost guard's estimate (cost.py), solver choices (solver_choice.py),
the initial velocities (initial_velocities.py), the quasi-static sag of a hanging body
(sag.py), a body's geometric stiffening (stiffened_body.py) and the plastic parts
(plastic_parts.py).

Imports the schema stage (flexmvm.scenarios) and the stages below; the runs stage
(flexmvm.runs) is above it.
"""
