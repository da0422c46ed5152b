"""The hinge profiles by name (docs/architecture.md, "A new profile"): one row per profile, a
subclass of model.sections.Section, and the section of a hinge by its `profile`."""

from __future__ import annotations

from typing import Any

from .notches import NOTCHES
from .sections import Section, UniformPlate

#: The profiles by name: one row per profile (:func:`register` adds one at run time).
PROFILES: dict[str, type[Section]] = {cls.profile: cls for cls in (UniformPlate, *NOTCHES)}


def register(cls: type[Section]) -> type[Section]:
    """Add a profile to :data:`PROFILES` under its `profile` name (usable as a decorator)."""
    if not cls.profile:
        raise ValueError(f"{cls.__name__} has no profile name")
    PROFILES[cls.profile] = cls
    return cls


def section_of(hinge: Any, scale: Any) -> Section:
    """The section of a plate hinge (a mechanism.Hinge with E, thickness and width), by its
    `profile` (the uniform plate by default); `scale` the file unit's size in metres."""
    name = getattr(hinge, "profile", UniformPlate.profile)
    if name not in PROFILES:
        raise ValueError(f"unknown profile {name!r} (known: {', '.join(sorted(PROFILES))})")
    return PROFILES[name].from_hinge(hinge, scale)
