"""Text and/or image -> backend -> validated :class:`TerrainSpec` (the one entry point the CLI uses)."""

from __future__ import annotations

from pathlib import Path

from legged_gente.generation.backends import GenerationResult
from legged_gente.generation.spec import TerrainSpec, image_source, spec_name, text_source

BACKENDS = ("planner", "openai")
SERVER_DEFAULTS = {"timeout": 60.0, "max_retries": 3, "api_key_env": "GENTE_API_KEY"}
"""The model server's settings and their defaults (``generate_spec``'s, gente-generate's flags'); the planner sends
no request, so it refuses any other value of them."""


def generate_spec(
    text: str | None = None,
    image: str | Path | bytes | None = None,
    backend: str = "planner",
    *,
    seed: int = 0,
    size_x: float = 20.0,
    size_y: float = 20.0,
    resolution: float = 0.1,
    name: str | None = None,
    base_url: str | None = None,
    model: str | None = None,
    two_phase: bool = False,
    vision_model: str | None = None,
    timeout: float = SERVER_DEFAULTS["timeout"],
    max_retries: int = SERVER_DEFAULTS["max_retries"],
    api_key_env: str = SERVER_DEFAULTS["api_key_env"],
    toolset: str = "ours",
) -> tuple[TerrainSpec, GenerationResult]:
    """Run ``backend`` on the inputs and return the validated spec and the backend's result (warnings, notes).

    ``toolset="gente"`` (openai backend) serves GenTe's original tool list and translates its calls.
    """
    if toolset != "ours" and backend != "openai":
        raise ValueError(f"toolset {toolset!r} is for the openai backend; the planner calls our tools.")
    server = {"timeout": timeout, "max_retries": max_retries, "api_key_env": api_key_env}
    if backend == "planner" and (base_url or model or two_phase or vision_model or server != SERVER_DEFAULTS):
        raise ValueError("base_url, model, two_phase, vision_model, timeout, max_retries and api_key_env are for the "
                         "openai backend; the planner sends no request.")
    if not text and image is None:
        raise ValueError("give a text description, an image, or both.")
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}; use one of {list(BACKENDS)}.")
    image_bytes = None
    if image is not None:
        from legged_gente.generation.backends.image import open_image

        image_bytes = Path(image).read_bytes() if isinstance(image, (str, Path)) else bytes(image)
        open_image(image_bytes, image)  # readable, or an error naming the file
    if backend == "planner":
        if image_bytes is not None:
            from legged_gente.generation.backends.image import plan_image

            result = plan_image(image_bytes, size_x, size_y, resolution=resolution)
            if text:
                result.warnings.append("the planner reads the image only; the text just names the terrain "
                                       "(use --backend openai to combine both).")
        else:
            from legged_gente.generation.backends.planner import plan_text

            result = plan_text(text, size_x, size_y, resolution=resolution)
    else:
        if not base_url or not model:
            raise ValueError("the openai backend needs --base-url (e.g. http://localhost:8000/v1) and --model.")
        from legged_gente.generation.backends.openai_backend import OpenAIBackend

        client = OpenAIBackend(
            base_url, model, api_key_env=api_key_env, timeout=timeout, max_retries=max_retries,
            two_phase=two_phase, vision_model=vision_model, size_x=size_x, size_y=size_y, resolution=resolution,
            toolset=toolset,
        )
        result = client.generate(text=text, image=image_bytes)
    if image_bytes is not None:
        source = image_source(image_bytes, Path(image).name if isinstance(image, (str, Path)) else None)
        if text:
            source["text"] = text
    else:
        source = text_source(text)
    if backend == "openai" and toolset != "ours":
        source["toolset"] = toolset
    if backend == "openai" and vision_model:  # the model that described the image (two_phase); ``model`` made the calls
        source["vision_model"] = vision_model
    smoothing = None
    if backend == "openai" and toolset == "gente":
        from legged_gente.generation.gente_compat import gente_smoothing

        smoothing = gente_smoothing("multi", size_x, size_y)  # GenTe smooths every tile after its calls
    default_name = spec_name(text) if text else (spec_name(Path(image).stem) if isinstance(image, (str, Path)) else "generated_terrain")
    spec = TerrainSpec(
        calls=result.calls, name=name or default_name, size_x=size_x, size_y=size_y, resolution=resolution,
        seed=seed, source=source, backend=backend, model=model if backend == "openai" else None, smoothing=smoothing,
    ).validated()
    from legged_gente.generation.checker import water_wall_problem  # a model easily paints a pond on flat ground

    wall = water_wall_problem(*spec.build(), spec.resolution)
    if wall:
        result.warnings.append(wall)
    return spec, result
