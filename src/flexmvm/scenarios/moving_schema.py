"""``[bodies.model.moving]``: the windows of a moving region (kind ``mvm-moving``, issue 53;
reduction/kinds/mvm_moving.py, integrate/moving_region.py). Other kinds ignore it, so a scenario
may carry it under ``kind = "full"`` and ``flexmvm run --model mvm-moving`` use it."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, model_validator

from flexmvm.integrate.moving_region import MovingOutside
from flexmvm.scenarios.fields import Frozen, Num, Positive, SetName
from flexmvm.scenarios.problems import problem


class MovingConfig(Frozen):
    """``moving = {path = "top", spacing_m = ..., half_width_m = ...}``: windows along the node
    set ``path`` (its principal axis), one every ``spacing_m`` [m], each holding the path nodes
    within ``half_width_m`` [m] of its centre (>= spacing / 2; for a point contact: (1/2 +
    0.2) spacing + the contact's facet size keeps the nodes it loads in the window);
    ``outside``: what a run does when the contact reaches a place no window covers ("warn":
    it says so and goes on, "stop": it fails there keeping what it computed); ``s_range_m``:
    the windows' span along the path [m, from the path nodes' centroid] (default: the path)."""

    path: SetName
    spacing_m: Positive
    half_width_m: Positive
    outside: MovingOutside = MovingOutside.WARN
    s_range_m: tuple[Num, Num] | None = None

    @model_validator(mode="after")
    def _check(self) -> MovingConfig:
        if self.half_width_m < 0.5 * self.spacing_m:
            raise problem(
                f"must be >= spacing_m / 2 = {0.5 * self.spacing_m:g}, got {self.half_width_m:g}",
                "half_width_m",
            )
        if self.s_range_m is not None and not self.s_range_m[0] < self.s_range_m[1]:
            raise problem(f"must be [low, high] with low < high, got {self.s_range_m}", "s_range_m")
        return self


#: ModelConfig's key, left out of a dump when not given (the dumps, and the cache and study keys
#: that hash them, stay those of before the key existed)
MovingKey = Annotated[MovingConfig | None, Field(exclude_if=lambda value: value is None)]
