"""``TerrainSpec``: the versioned JSON document a generation produces and training reads.

A spec is the tile's size, resolution and seed, the ordered validated tool calls with their regions, and
provenance (the prompt text or the image's sha256, the backend and the model). It builds the same
heightfield and material map every time: the terrain library's ``TileSpec.build`` is deterministic from
the seed, and the stored calls carry every parameter (defaults filled in at validation).

Example document::

    {"version": 1, "name": "forest_trail", "size_x": 20.0, "size_y": 20.0, "resolution": 0.1, "seed": 0,
     "calls": [{"tool": "natural_ground", "region": "full", "mode": "set", "params": {...}},
               {"tool": "soil", "region": {"x0": 0, "y0": 0, "x1": 10, "y1": 20}, "params": {...}}],
     "source": {"text": "a forest trail"}, "backend": "planner", "model": null}
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
from pathlib import Path
from typing import Any

import numpy as np

from legged_gente.generation.validation import SPEC_VERSION, ToolCall, ValidationError, validate_spec_dict
from legged_gente.terrain.materials import MaterialMap


def text_source(text: str) -> dict[str, Any]:
    return {"text": text}


def image_source(data: bytes, name: str | None = None) -> dict[str, Any]:
    """Provenance of an image: its sha256 (the bytes are not stored) and, if given, its file name."""
    out: dict[str, Any] = {"image_sha256": hashlib.sha256(data).hexdigest()}
    if name:
        out["image_name"] = name
    return out


def spec_name(text: str, default: str = "generated_terrain") -> str:
    """A snake_case identifier from the first words of ``text`` (used for spec and class names)."""
    words = [w for w in re.findall(r"[a-z0-9]+", text.lower()) if w not in ("a", "an", "the", "of", "with")][:4]
    name = "_".join(words)
    return name if name and name[0].isalpha() else default


@dataclasses.dataclass
class TerrainSpec:
    """A generated terrain: tile geometry, seed, ordered validated calls and provenance."""

    calls: list[ToolCall]
    name: str = "generated_terrain"
    size_x: float = 20.0
    size_y: float = 20.0
    resolution: float = 0.1
    seed: int = 0
    source: dict[str, Any] = dataclasses.field(default_factory=dict)
    backend: str = "planner"
    model: str | None = None
    version: int = SPEC_VERSION

    def to_dict(self) -> dict[str, Any]:
        return {
            "version": self.version,
            "name": self.name,
            "size_x": float(self.size_x),
            "size_y": float(self.size_y),
            "resolution": float(self.resolution),
            "seed": int(self.seed),
            "calls": [c.to_dict() for c in self.calls],
            "source": dict(self.source),
            "backend": self.backend,
            "model": self.model,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any], registry: Any = None) -> "TerrainSpec":
        """Validate ``data`` (schema, every call against its tool) and build the spec; raises ValidationError."""
        data, calls = validate_spec_dict(data, registry)
        fields = {k: data[k] for k in ("name", "size_x", "size_y", "resolution", "seed", "source", "backend", "model")}
        return cls(calls=calls, version=data["version"], **fields)

    def validated(self, registry: Any = None) -> "TerrainSpec":
        """A re-validated copy (e.g. after editing calls by hand)."""
        return TerrainSpec.from_dict(self.to_dict(), registry)

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2) + "\n"

    def save(self, path: str | Path) -> Path:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(self.to_json())
        return path

    @classmethod
    def load(cls, path: str | Path, registry: Any = None) -> "TerrainSpec":
        path = Path(path)
        try:
            data = json.loads(path.read_text())
        except FileNotFoundError:
            raise FileNotFoundError(f"terrain spec {path} does not exist; pass the spec.json that gente-generate wrote.") from None
        except json.JSONDecodeError as exc:
            raise ValidationError([f"spec {path}: not valid JSON ({exc})."]) from None
        try:
            return cls.from_dict(data, registry)
        except ValidationError as exc:
            raise ValidationError([f"{path}: {m}" for m in exc.messages]) from None

    def to_tile_spec(self):
        """The terrain library's ``TileSpec``: one ``Part`` per call, in call order (read as training reads it)."""
        from legged_gente.terrain.composition import tile_spec_from_document

        return tile_spec_from_document(self.to_dict())

    def build(self) -> tuple[np.ndarray, MaterialMap]:
        """Heights (float32 ``(nx, ny)``, metres) and the aligned MaterialMap; deterministic."""
        return self.to_tile_spec().build()
