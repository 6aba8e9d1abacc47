"""How a scenario problem reaches the user: one :class:`ScenarioError` line naming the source,
the key path and the problem, e.g. ``rod_impact.toml: contacts[0].master: unknown body 'b3'
(bodies: b1, b2)``. Validators raise :func:`problem`; :func:`format_error` turns one pydantic
error into the line's ``key.path: problem`` part.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from pydantic import BaseModel, ValidationError
from pydantic_core import PydanticCustomError

from flexmvm.errors import InputError

ERROR_TYPE = "flexmvm_scenario"


class ScenarioError(InputError):
    """A scenario that cannot be used: one line with source, key path and problem."""


def problem(text: str, key: str = "") -> PydanticCustomError:
    """Error for a validator; ``key`` is appended to the location pydantic reports."""
    return PydanticCustomError(ERROR_TYPE, "{problem}", {"problem": text, "key": key})


_UNION_TAGS: dict[int | str, tuple[str, ...]] = {
    "material": ("preset", "inline"),
    "hf_damping_time_s": ("number", "auto"),
}


def _format_loc(loc: tuple[int | str, ...], extra: str) -> str:
    out = ""
    for k, part in enumerate(loc):
        if isinstance(part, int):
            out += f"[{part}]"
        elif k > 0 and part in _UNION_TAGS.get(loc[k - 1], ()):
            continue  # a tagged union's branch (the material's, the damping time's)
        else:
            out += f".{part}" if out else str(part)
    if extra:
        out += extra if extra.startswith("[") or not out else f".{extra}"
    return out or "(top level)"


_BOUNDS = {
    "greater_than": ("gt", ">"),
    "greater_than_equal": ("ge", ">="),
    "less_than": ("lt", "<"),
    "less_than_equal": ("le", "<="),
}


def format_error(err: Any) -> str:
    """One line 'key.path: problem' from one pydantic error dict."""
    ctx = err.get("ctx") or {}
    if err["type"] == ERROR_TYPE:
        return f"{_format_loc(err['loc'], ctx.get('key', ''))}: {ctx['problem']}"
    where = _format_loc(err["loc"], "")
    if err["type"] == "extra_forbidden":
        return f"{where}: unknown key"
    if err["type"] == "missing":
        return f"{where}: missing required key"
    if err["type"] in _BOUNDS:
        name, op = _BOUNDS[err["type"]]
        bound = ctx[name]
        msg = (
            f"must be {op} {bound:g}"
            if isinstance(bound, (int, float))
            else f"must be {op} {bound}"
        )
    elif err["type"] == "too_short":
        msg = f"needs at least {ctx.get('min_length', 1)} entry"
    else:
        msg = err["msg"][:1].lower() + err["msg"][1:]
    shown = repr(err["input"])
    shown = shown if len(shown) <= 60 else shown[:57] + "..."
    return f"{where}: {msg}, got {shown}".replace("\n", " ")


def validate_part(cls: type[BaseModel], data: Mapping[str, Any], source: str, key: str = ""):
    """``cls`` validated from ``data`` (values or model instances); ScenarioError (one line:
    source, key path, problem) otherwise."""
    try:
        return cls.model_validate(dict(data))
    except ValidationError as exc:
        errors = exc.errors()
        more = f" (and {len(errors) - 1} more problem(s))" if len(errors) > 1 else ""
        line = format_error(errors[0])
        if key:
            top = "(top level)"
            line = key + (line[len(top) :] if line.startswith(top) else f".{line}")
        raise ScenarioError(f"{source}: {line}{more}") from None
