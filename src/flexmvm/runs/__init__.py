"""Runs: a Scenario built (flexmvm.assembly) and simulated, and what is made of the run: the
run and its summary (run.py), the main job of `flexmvm run` (main_job.py), the guards of a
run's validity (guard.py: reduced-basis contact, blowup.py: energy growth), the energy report
(energy_report.py), the plastic summary (plastic_summary.py), comparisons of runs
(compare.py), the key of a stored run (provenance.py), a run stored in a directory
(stored_run.py) and a written run read back with its Scenario (written_run.py: fm.read_run).
Code for one shipped scenario file only is in showcases/.
"""
