"""gente-generate: text or an image -> validated terrain spec -> terrain_cfg.py + spec.json + preview.png.

Examples::

    gente-generate --text "a forest trail along a knee-deep stream" --out terrains/forest
    gente-generate --image sketch.png --out terrains/sketch
    gente-generate --text "a rocky beach" --backend openai --base-url http://localhost:8000/v1 --model qwen --out terrains/beach

Exit status 2: bad input (a flag, the image, --base, --out, the API key's variable), refused before any model is
asked where it can be; 1: the server or the model failed.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import traceback
from pathlib import Path

from legged_gente.generation.backends import MAX_RETRIES, MAX_TIMEOUT, GenerationError
from legged_gente.generation.backends.image import open_image
from legged_gente.generation.backends.openai_backend import base_url_problem, shown_url
from legged_gente.generation.emit import DEFAULT_BASE, emit, resolve_base
from legged_gente.generation.pipeline import BACKENDS, SERVER_DEFAULTS, generate_spec
from legged_gente.generation.validation import (
    MAX_STRING_CHARS,
    ValidationError,
    printable,
    spec_field_problem,
    tile_problem,
)
from legged_gente.utils.args import Parser, add_verbose, check_output, flag, one_line, quiet_third_party, seed


def _positive(most: float = math.inf):
    """An argparse type: a float > 0, finite and at most ``most`` (float() reads 'nan' and 'inf' too)."""
    bound = "finite" if most == math.inf else f"at most {most:g}"

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not (0 < value <= most and math.isfinite(value)):
            raise argparse.ArgumentTypeError(f"must be > 0 and {bound}, got {text}")
        return value

    return parse


def _error(exc: BaseException, code: int, verbose: bool) -> int:
    """The error as one line (its traceback before it with ``--verbose``); ``code``, the exit status."""
    if verbose:
        traceback.print_exc()
    print(f"gente-generate: error: {printable(one_line(exc))}", file=sys.stderr)
    return code


def build_parser() -> Parser:
    p = Parser(prog="gente-generate", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    src = p.add_argument_group("input (at least one)")
    src.add_argument("--text", help="scene description, e.g. 'a knee-deep river in a forest'")
    src.add_argument("--image", type=Path, help="photo or colour-coded sketch map (PNG/JPEG); see docs/generation.md")
    p.add_argument("--out", required=True, help="output directory (terrain_cfg.py, spec.json, preview.png)")
    p.add_argument("--backend", choices=BACKENDS, default="planner", help="planner (offline, default) or openai")
    p.add_argument(*flag("--base-url"), help="OpenAI-compatible server, e.g. http://localhost:8000/v1 (openai backend)")
    p.add_argument(*flag("--model"), help="model name on that server (openai backend)")
    p.add_argument(*flag("--vision-model"), help="model that describes the image in --two-phase (default: --model)")
    p.add_argument(*flag("--two-phase"), action="store_true", help="VLM describes the image, then the LLM calls the tools")
    p.add_argument("--toolset", choices=("ours", "gente"), default="ours",
                   help="openai backend: serve our tools (default) or GenTe's original tool list, translated")
    p.add_argument(*flag("--api-key-env"), help=f"environment variable holding the API key (openai backend; default {SERVER_DEFAULTS['api_key_env']}, 'none' if that is unset; a variable named here must be set)")
    p.add_argument("--timeout", type=_positive(MAX_TIMEOUT), help=f"request timeout in seconds (openai backend; default {SERVER_DEFAULTS['timeout']:g})")
    p.add_argument(*flag("--max-retries"), type=int, help=f"correction rounds for invalid tool calls (openai backend; default {SERVER_DEFAULTS['max_retries']}, at most {MAX_RETRIES})")
    p.add_argument("--seed", type=seed, default=0, help="terrain seed (default 0)")
    p.add_argument("--size", type=_positive(), default=20.0, help="tile side in metres (default 20)")
    p.add_argument("--resolution", type=_positive(), default=0.1, help="cell size in metres (default 0.1)")
    p.add_argument("--name", help="terrain name (snake_case); default from the text or image file name")
    p.add_argument("--base", default=DEFAULT_BASE, help=f"terrain config class to subclass (default {DEFAULT_BASE})")
    p.add_argument("--mesh", choices=("obj", "glb", "ply", "stl"), help="also write the terrain as a mesh")
    add_verbose(p)
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    quiet_third_party(args.verbose)
    if args.text is not None and any("\udc80" <= ch <= "\udcff" for ch in args.text):  # bytes not UTF-8
        parser.error("--text is not valid UTF-8 (the shell passed bytes of another encoding); give it in UTF-8.")
    if args.api_key_env is not None and not args.api_key_env.strip():
        parser.error("--api-key-env is empty; name the environment variable that holds the key, e.g. GENTE_API_KEY.")
    if args.text is not None and not args.text.strip():
        parser.error("--text is empty; describe the scene, e.g. --text 'a knee-deep river in a forest'.")
    if not args.text and args.image is None:
        parser.error("give --text, --image, or both.")
    if args.image is not None and not args.image.is_file():
        parser.error(f"--image {args.image} is not a file.")
    if args.backend == "openai" and not (args.base_url and args.model):
        parser.error("--backend openai needs --base-url and --model.")
    url_problem = args.base_url and base_url_problem(args.base_url)
    if url_problem:
        parser.error(f"--base-url {printable(shown_url(args.base_url)[:200])}: {url_problem}.")
    if args.backend == "planner" and (args.base_url or args.model or args.vision_model or args.two_phase
                                      or args.toolset != "ours"):
        parser.error("--base-url/--model/--vision-model/--two-phase/--toolset are for --backend openai.")
    if args.backend == "openai" and args.api_key_env is not None and args.api_key_env not in os.environ:
        parser.error(f"--api-key-env {args.api_key_env}: the variable is not set; export it with the key, or leave out "
                     f"--api-key-env for a server without one.")
    for name, default in SERVER_DEFAULTS.items():
        if getattr(args, name) is None:
            setattr(args, name, default)
        elif args.backend == "planner":
            parser.error(f"--{name.replace('_', '-')} is for --backend openai (the planner sends no request); leave "
                         f"it out or add --backend openai.")
    if args.two_phase and args.image is None:
        parser.error("--two-phase describes the --image first; give --image or leave out --two-phase.")
    if args.vision_model and not args.two_phase:
        parser.error("--vision-model describes the image in --two-phase; add --two-phase (and --image) or leave it "
                     "out.")
    if not 0 <= args.max_retries <= MAX_RETRIES:
        parser.error(f"--max-retries must be between 0 and {MAX_RETRIES}, got {args.max_retries}.")
    # the spec's own limits, checked before anything is generated
    if args.text is not None and len(args.text) > MAX_STRING_CHARS:
        parser.error(f"--text: has {len(args.text)} characters; at most {MAX_STRING_CHARS} are allowed.")
    for option, field, value in (("--size", "size_x", args.size), ("--resolution", "resolution", args.resolution),
                                 ("--name", "name", args.name), ("--model", "model", args.model)):
        problem = None if value is None else spec_field_problem(field, value)
        if problem:
            parser.error(f"{option} {value:g}: {problem}." if isinstance(value, float) else f"{option}: {problem}.")
    problem = tile_problem(args.size, args.size, args.resolution)
    if problem:
        parser.error(f"--size {args.size:g} with --resolution {args.resolution:g}: {problem}.")
    # the inputs and the output folder, checked before any model is asked
    try:
        check_output(args.out, "--out")
    except ValueError as exc:
        parser.error(one_line(exc))
    try:
        if args.image is not None:
            open_image(args.image.read_bytes(), args.image)
    except (ValueError, OSError) as exc:
        parser.error(f"--image: {one_line(exc)}")
    try:
        resolve_base(args.base)
    except ValueError as exc:
        parser.error(f"--base: {one_line(exc)}")
    try:
        spec, result = generate_spec(
            args.text, args.image, args.backend, seed=args.seed, size_x=args.size, size_y=args.size,
            resolution=args.resolution, name=args.name, base_url=args.base_url, model=args.model,
            two_phase=args.two_phase, vision_model=args.vision_model, timeout=args.timeout,
            max_retries=args.max_retries, api_key_env=args.api_key_env, toolset=args.toolset,
        )
        for note in result.notes:  # a two-phase note is the vision model's text
            print(f"note: {printable(note)}")
        print(f"{len(spec.calls)} tool call(s):")
        for call in spec.calls:
            print(f"  {call.tool}({json.dumps(call.arguments())})")
        for warning in result.warnings:
            print(f"warning: {printable(warning)}", file=sys.stderr)
        held = Path(args.out, "spec.json")  # a benchmark item's folder, perhaps: say when its terrain changed
        before = held.read_bytes() if held.is_file() else None
        out = emit(spec, args.out, base=args.base, mesh=args.mesh)
        if before is not None and before != held.read_bytes():
            print(f"note: replaced the terrain {args.out} held (its spec.json and the files beside it); evaluations "
                  f"of the old one are no longer comparable with new ones there", file=sys.stderr)
    except (ValidationError, GenerationError) as exc:  # the server or the model failed; the planner asks none, so
        return _error(exc, 1 if args.backend == "openai" else 2, args.verbose)  # its refusal: the text, image or tile
    except (ValueError, OSError) as exc:  # the user's input (e.g. the API key's variable) or the output folder
        return _error(exc, 2, args.verbose)
    print(f"wrote {out.module} (class {out.class_name}), {out.spec}, {out.preview}" + (f", {out.mesh}" if out.mesh else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
