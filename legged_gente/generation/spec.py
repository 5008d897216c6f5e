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

A spec may also name a heightmap as the ground under its calls (an imported GenTe ``array.npy``, a survey)::

    {..., "resolution": 0.1, "size_x": 20.0, "size_y": 20.0,
     "heightmap": {"file": "array.npy", "vertical_scale": 0.005}, "calls": []}

``file`` is relative to the spec file; the cell size is ``resolution``, and the sizes must be the map's cells
times it. Nothing about the map is guessed: a wrong size, a wrapped-around (overflowed) integer map or one
beyond the height bound is refused with the reason.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
import unicodedata
from pathlib import Path
from typing import Any

import numpy as np

from legged_gente.generation.validation import (
    MAX_SPEC_BYTES,
    ToolCall,
    ValidationError,
    parse_json,
    validate_spec_dict,
)
from legged_gente.terrain.composition import SPEC_SCHEMA, SPEC_VERSION
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
    """A snake_case identifier from the first words of ``text`` (used for spec and class names), cut to the longest
    name a spec allows. Letters are first taken to ASCII (compatibility forms split, accents dropped: "été plage" is
    "ete_plage", the ligature "ﬁ" is "fi")."""
    ascii_text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode()
    words = [w for w in re.findall(r"[a-z0-9]+", ascii_text.lower()) if w not in ("a", "an", "the", "of", "with")]
    while words and not words[0][0].isalpha():  # a name starts with a letter: "123 rivers" is "rivers"
        words.pop(0)
    name = "_".join(words[:4])[: SPEC_SCHEMA["properties"]["name"]["maxLength"]]
    return name or default


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
    heightmap: dict[str, Any] | None = None
    """``{"file", "vertical_scale"}``: the ground under the calls (None: flat 0 m)."""
    smoothing: list[dict[str, Any]] | None = None
    """``[{"region", "axis", "sigma"}]``: Gaussian filters of the heights after the geometric calls (None: none)."""
    base_dir: Path | None = dataclasses.field(default=None, compare=False, repr=False)
    """Folder a relative heightmap ``file`` is read from (the spec file's; None: the working directory)."""

    def to_dict(self) -> dict[str, Any]:
        extra = {} if self.heightmap is None else {"heightmap": dict(self.heightmap)}
        if self.smoothing:
            extra["smoothing"] = [dict(f) for f in self.smoothing]
        return extra | {
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
    def from_dict(cls, data: dict[str, Any], registry: Any = None, base_dir: str | Path | None = None) -> "TerrainSpec":
        """Validate ``data`` (schema, heightmap, every call against its tool) and build the spec; raises
        ValidationError. A relative heightmap file is read from ``base_dir``."""
        data, calls = validate_spec_dict(data, registry, base_dir)
        fields = {k: data[k] for k in ("name", "size_x", "size_y", "resolution", "seed", "source", "backend", "model")}
        base = None if base_dir is None else Path(base_dir)
        return cls(calls=calls, version=data["version"], heightmap=data.get("heightmap"),
                   smoothing=data.get("smoothing"), base_dir=base, **fields)

    def validated(self, registry: Any = None) -> "TerrainSpec":
        """A re-validated copy (e.g. after editing calls by hand)."""
        return TerrainSpec.from_dict(self.to_dict(), registry, self.base_dir)

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2) + "\n"

    def save(self, path: str | Path) -> Path:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(self.to_json(), encoding="utf-8")
        return path

    @classmethod
    def load(cls, path: str | Path, registry: Any = None) -> "TerrainSpec":
        """Read and validate a spec file; a bad file raises ValidationError naming the file and the problem."""
        path = Path(path)
        try:
            size = path.stat().st_size
        except FileNotFoundError:
            raise FileNotFoundError(f"terrain spec {path} does not exist; pass the spec.json that gente-generate wrote.") from None
        if not path.is_file():
            raise ValidationError([f"spec {path} is not a file; pass the spec.json that gente-generate wrote."])
        if size > MAX_SPEC_BYTES:
            raise ValidationError([f"spec {path}: the file is {size} bytes; a spec is at most {MAX_SPEC_BYTES} bytes."])
        try:
            data = parse_json(path.read_bytes(), "the file's contents", MAX_SPEC_BYTES)
            return cls.from_dict(data, registry, path.parent)
        except ValidationError as exc:
            raise ValidationError([f"{path}: {m}" for m in exc.messages]) from None

    def terrain_digest(self) -> str:
        """A short sha256 of what builds the terrain (sizes, seed, calls, smoothing, the heightmap's scale and its
        file's bytes), not of its name or source: two reports compare the same terrain when their digests agree."""
        d = self.to_dict()
        built = {k: d[k] for k in ("size_x", "size_y", "resolution", "seed", "calls", "smoothing", "heightmap") if k in d}
        digest = hashlib.sha256(json.dumps(built, sort_keys=True).encode())
        if self.heightmap is not None:
            digest.update(((self.base_dir or Path.cwd()) / self.heightmap["file"]).read_bytes())
        return digest.hexdigest()[:16]

    def to_tile_spec(self):
        """The terrain library's ``TileSpec``: one ``Part`` per call, in call order (read as training reads it)."""
        from legged_gente.terrain.composition import tile_spec_from_document

        return tile_spec_from_document(self.to_dict(), self.base_dir)

    def build(self) -> tuple[np.ndarray, MaterialMap]:
        """Heights (float32 ``(nx, ny)``, metres) and the aligned MaterialMap; deterministic."""
        return self.to_tile_spec().build()
