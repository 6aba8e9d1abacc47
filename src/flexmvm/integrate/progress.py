"""The step bar of a run (integrate.driver): simulated time, steps, time left."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from tqdm import tqdm


class StepProgress:
    """The step bar: simulated time [us] of the run's span, the steps taken beside it. Made at
    the first output after the first step, so that its rate and time left leave out what the
    first step pays once (kernels compiled, the first factorizations); tqdm's moving average
    (smoothing) then follows the contact's finer steps as they come."""

    def __init__(self, enabled: bool, n_ticks: int, dt: float):
        self.enabled, self.n_ticks, self.dt = enabled, n_ticks, dt
        self.bar: tqdm | None = None  # made by the first update

    def update(self, tick: int, n_steps: int) -> None:
        if not self.enabled:
            return
        done_us = tick * self.dt * 1e6
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(
                total=round(self.n_ticks * self.dt * 1e6, 3),
                initial=round(done_us, 3),
                unit="us",
                desc="simulating",
                leave=False,
                mininterval=0.5,
                smoothing=0.1,
                bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.1f}/{total:.1f} us "
                "[{elapsed}<{remaining}]{postfix}",
            )
        self.bar.set_postfix_str(f"{n_steps} steps", refresh=False)
        self.bar.update(round(done_us - self.bar.n, 3))

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
