"""Code that belongs to one shipped scenario file (the repository's scenarios/), not to the
stage: the pendulum release's event measures (pendulum.py, scenarios/pendulum_release.toml)
and the sphere on block's Hertz check (hertz_block.py, scenarios/sphere_block.toml). The runs
stage may import it (a pendulum run's summary and figure); nothing below the runs stage does.
"""
