"""legged_gym-style configuration: nested classes, changed by subclassing, instantiated per run."""

from __future__ import annotations

import copy
import dataclasses
import inspect


class BaseConfig:
    """A config class whose nested classes become (independent) instances when it is constructed.

    Subclass to change a robot or task; construct to get a mutable copy that command-line arguments may
    override without touching the class itself.
    """

    def __init__(self) -> None:
        _instantiate_nested(self)


def _instantiate_nested(obj: object) -> None:
    for name in dir(obj):
        if name.startswith("__"):
            continue
        value = getattr(obj, name)
        if inspect.isclass(value):
            instance = value()
            setattr(obj, name, instance)
            _instantiate_nested(instance)
        elif dataclasses.is_dataclass(value):  # a term record (ObsTerm): each config instance gets its own copy
            setattr(obj, name, dataclasses.replace(value))
        elif isinstance(value, (list, dict, set)):  # an edit in place (cfg.control.stiffness["knee"] = 1) stays in
            setattr(obj, name, copy.deepcopy(value))  # this instance, not in the class and every later config


def class_to_dict(obj: object) -> dict | object:
    """Public attributes of a config instance (recursively) as plain dicts and lists."""
    if not hasattr(obj, "__dict__") and not inspect.isclass(obj):
        return obj
    result = {}
    for name in dir(obj):
        if name.startswith("_"):
            continue
        value = getattr(obj, name)
        if callable(value) and not inspect.isclass(value):
            continue
        if isinstance(value, (list, tuple)):
            result[name] = [class_to_dict(v) for v in value]
        elif hasattr(value, "__dict__") or inspect.isclass(value):
            result[name] = class_to_dict(value)
        else:
            result[name] = value
    return result


def update_from_dict(obj: object, values: dict, path: str = "cfg") -> None:
    """Set attributes of a config instance from a (nested) dict; unknown keys raise with the valid ones."""
    for key, value in values.items():
        if not hasattr(obj, key):
            valid = sorted(k for k in dir(obj) if not k.startswith("_"))
            raise AttributeError(f"{path} has no attribute {key!r}; valid attributes: {valid}")
        current = getattr(obj, key)
        if isinstance(value, dict) and hasattr(current, "__dict__") and not isinstance(current, dict):
            update_from_dict(current, value, f"{path}.{key}")
        else:
            setattr(obj, key, value)


def near_misses(cfg: type | object, path: str, open_sections: tuple[str, ...] = ()) -> list[str]:
    """Names a config class (or a nested section class of it) brings in that none of its bases has, but that lie
    a slip or two (``typing_slips``) from one its bases declare, each as a sentence. A misspelt field in a subclass
    (``paper_drag_aera = True``) is a new attribute to Python, which nothing reads, while the parent's value stays
    in force; a name further from every declared one is the user's own setting and is left alone. Given a config
    instance, also the names set on it and its sections that their classes do not declare
    (``cfg.domain_rand.push_robot = False`` in a script). ``open_sections`` (dotted paths below ``path``) hold the
    user's own names (reward scales, observation terms) and are not looked into."""
    cls = cfg if inspect.isclass(cfg) else type(cfg)
    found = []
    inherited = {n for base in cls.__mro__[1:] for n in dir(base) if not n.startswith("_")}
    for name in (n for n in vars(cls) if not n.startswith("_") and n not in inherited):
        meant = _closest(name, inherited)
        if meant:
            found.append(f"{path}.{name} (in {cls.__qualname__}) is not a setting its parents declare, so nothing "
                         f"reads it; did you mean {path}.{meant}?")
    if not inspect.isclass(cfg):
        declared = {n for n in dir(cls) if not n.startswith("_")}
        for name in (n for n in vars(cfg) if not n.startswith("_") and n not in declared):
            meant = _closest(name, declared)
            if meant:
                found.append(f"{path}.{name} was set on the config instance but is not a setting of its class, so "
                             f"nothing reads it; did you mean {path}.{meant}?")
    for name in (n for n in dir(cls) if not n.startswith("_")):
        here = f"{path}.{name}"
        if inspect.isclass(getattr(cls, name)) and here.split(".", 1)[-1] not in open_sections:
            found += near_misses(getattr(cfg, name), here, open_sections)
    return found


def _closest(name: str, declared: set[str]) -> str | None:
    """The declared name ``name`` is a slip or two from (one for names shorter than 6 letters), if any."""
    close = [d for d in declared if typing_slips(name, d) <= (2 if len(d) >= 6 else 1)]
    return min(close, key=lambda d: (typing_slips(name, d), d)) if close else None


def typing_slips(a: str, b: str) -> int:
    """How many letters missing, added, changed or swapped with their neighbour turn ``a`` into ``b`` (the optimal
    string alignment distance): a misspelt name is one or two slips from the intended one, while a name of the
    user's own (``swing_height_target`` beside ``base_height_target``) is several."""
    prev2, prev = None, list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        row = [i] + [0] * len(b)
        for j, cb in enumerate(b, 1):
            row[j] = min(prev[j] + 1, row[j - 1] + 1, prev[j - 1] + (ca != cb))
            if prev2 is not None and i > 1 and j > 1 and ca == b[j - 2] and a[i - 2] == cb:
                row[j] = min(row[j], prev2[j - 2] + 1)
        prev2, prev = prev, row
    return prev[-1]
