"""Two evaluations of the same benchmark, compared terrain by terrain: is one policy better, or is the difference
within what two evaluations of one policy already differ by?

    python -m legged_gente.evaluation.compare eval_a/report.csv eval_b/report.csv [--metric success_rate]

For each terrain the difference B - A of the metric; their mean (each terrain weighs the same) and its standard
error, sample SD / sqrt(n) (a paired comparison: the terrains' own difficulty cancels). Per group too: the item
kinds and the categories of ``report.py``. A difference is "resolved" when it exceeds Student's t quantile for a
two-sided 95 % (n - 1 degrees of freedom: 2.0 for many terrains, 3.2 for 4, 12.7 for 2) times its standard error;
a group of fewer than ``MIN_TERRAINS`` terrains gets no verdict.
Choose between training candidates on ``gente_val`` this way, and report on gente100 and gente_original.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

from scipy.stats import t as student_t

from legged_gente.evaluation.benchmark import KINDS
from legged_gente.evaluation.report import CATEGORIES, METRIC_COLUMNS

METRIC_UNITS = {"tracking_error": " (m/s)", "heading_error": " (deg)", "distance": " (m)", "displacement": " (m)",
                "energy_per_m": " (J/m)"}
"""The unit of a compared metric, for the table's title (rates are in points)."""
CONFIDENCE = 0.95
"""Two-sided: a mean difference is resolved beyond Student's t quantile (1 + CONFIDENCE) / 2 times its standard error."""
MIN_TERRAINS = 3
"""Fewer terrains than this in a group: no verdict (two differences alike give a standard error of about 0)."""


SCORING_SETTINGS = ("task_mode", "tracking_threshold", "min_progress", "min_speed", "stand_fraction",
                    "reach_distance", "speed", "episode_length_s", "settle_s", "tile_edge_margin", "max_base_speed")
"""The settings of report.json's ``meta`` that change what a terrain scores: two reports compared must agree on
them (the policy, seed, robots per terrain and device may differ)."""


def read_terrains(path: str | Path, metric: str) -> dict[str, tuple[set[str], float]]:
    """Terrain name -> (its groups: kind and categories, the metric), from a gente-evaluate report.csv."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file; give the report.csv that gente-evaluate --out wrote.")
    not_a_report = (f"{path} is not a gente-evaluate report.csv (columns row, name, kind, categories, then the "
                    f"metrics)")
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
    except (UnicodeDecodeError, csv.Error) as error:
        raise ValueError(f"{not_a_report}: {error}; give the report.csv that gente-evaluate --out wrote.") from None
    if not rows or not {"row", "name", "kind", "categories"} <= set(rows[0]):
        raise ValueError(f"{not_a_report}; give the report.csv that gente-evaluate --out wrote.")
    for line, row in enumerate(rows, start=2):
        if None in row or None in row.values():  # fields missing or extra: a file cut short, or edited
            raise ValueError(f"{path}, line {line}: {len(row) - (None in row)} fields where the header has "
                             f"{len(rows[0]) - (None in rows[0])} (cut short or edited); evaluate again.")
    if metric not in rows[0]:
        raise ValueError(f"--metric {metric}: {path} has no such column; give one of {', '.join(METRIC_COLUMNS)}.")
    terrains = {}
    for row in rows:
        if row["row"] == "terrain":
            try:
                value = float(row[metric]) if row[metric] else math.nan
            except ValueError:
                raise ValueError(f"--metric {metric}: {path} holds {row[metric]!r} there, not a number; give a numeric "
                                 f"column: {', '.join(METRIC_COLUMNS)}.") from None
            terrains[row["name"]] = ({row["kind"], *filter(None, row["categories"].split("+"))}, value)
    return terrains


def check_made_alike(a: Path, b: Path) -> None:
    """The two reports' scoring settings (``SCORING_SETTINGS``, from the report.json beside each report.csv) agree:
    a difference between, say, a 10 s velocity evaluation and a waypoint one is no difference between policies.
    Without a report.json beside one, that is said and the comparison goes on."""
    metas = []
    for path in (a, b):
        beside = path.parent / "report.json"
        try:
            metas.append(json.loads(beside.read_text())["meta"])
        except FileNotFoundError:
            print(f"no report.json beside {path}: the two evaluations' settings are not checked")
            return
        except (ValueError, KeyError, TypeError) as error:
            raise ValueError(f"{beside} is not a gente-evaluate report.json ({type(error).__name__}: {error}); "
                             f"evaluate again.") from None
    differ = [f"{name} {metas[0].get(name)} against {metas[1].get(name)}" for name in SCORING_SETTINGS
              if metas[0].get(name) != metas[1].get(name)]
    if differ:
        raise ValueError(f"the two evaluations were scored differently ({'; '.join(differ)}, from their "
                         f"report.json); evaluate both with the same flags.")
    digests = [meta.get("terrain_digests") or {} for meta in metas]  # none in a report from before they were kept
    changed = sorted(name for name in digests[0].keys() & digests[1].keys() if digests[0][name] != digests[1][name])
    if changed:
        raise ValueError(f"the two evaluations built different terrains under the same name ({', '.join(changed[:5])}"
                         f"{' and more' if len(changed) > 5 else ''}: their spec changed between them, from their "
                         f"report.json); evaluate both on the same spec files.")


def compare_reports(a: str | Path, b: str | Path, metric: str = "success_rate") -> dict[str, dict]:
    """Per group ("all", the kinds, the categories present): terrains, mean of A, mean of B, mean difference
    B - A, its standard error (NaN for one terrain) and whether it is resolved."""
    a, b = (Path(p) / "report.csv" if Path(p).is_dir() else Path(p) for p in (a, b))  # a gente-evaluate --out folder
    first, second = read_terrains(a, metric), read_terrains(b, metric)
    check_made_alike(a, b)
    if first.keys() != second.keys():
        lacks, extra = sorted(first.keys() - second.keys()), sorted(second.keys() - first.keys())
        said = [f"lacks {lacks}"] * bool(lacks) + [f"has {extra} that {a} has not"] * bool(extra)
        raise ValueError(f"compare evaluations of the same benchmark: {b} {' and '.join(said)}.")
    pairs = {name: (groups, first[name][1], value) for name, (groups, value) in second.items()
             if math.isfinite(first[name][1]) and math.isfinite(value)}
    if not pairs:
        raise ValueError(f"no terrain has a {metric} in both {a} and {b} (empty where undefined, e.g. heading_error "
                         f"without a heading command); compare another --metric.")
    out = {}
    for group in ("all", *KINDS, *CATEGORIES):
        chosen = [(x, y) for groups, x, y in pairs.values() if group == "all" or group in groups]
        if not chosen:
            continue
        n = len(chosen)
        differences = [y - x for x, y in chosen]
        mean = sum(differences) / n
        se = math.sqrt(sum((d - mean) ** 2 for d in differences) / (n - 1) / n) if n > 1 else math.nan
        t = float(student_t.ppf((1 + CONFIDENCE) / 2, n - 1)) if n > 1 else math.nan
        out[group] = {"terrains": n, "a": sum(x for x, _ in chosen) / n, "b": sum(y for _, y in chosen) / n,
                      "difference": mean, "se": se, "t": t,
                      "resolved": bool(n >= MIN_TERRAINS and abs(mean) > t * se)}
    return out


def main(argv=None) -> None:
    from legged_gente.utils.args import Parser, run_command

    parser = Parser(prog="python -m legged_gente.evaluation.compare", description=__doc__.split("\n\n")[0])
    parser.add_argument("a", help="report.csv of evaluation A (or the --out folder holding it)")
    parser.add_argument("b", help="report.csv of evaluation B (or its folder; differences are B - A)")
    parser.add_argument("--metric", default="success_rate", help="a report column (default success_rate)")
    args = parser.parse_args(argv)

    def show(args) -> None:
        rows = compare_reports(args.a, args.b, args.metric)
        scale, unit = (100.0, " points") if args.metric.endswith("_rate") else (1.0, METRIC_UNITS.get(args.metric, ""))
        digits = 2 if scale == 100.0 or args.metric == "heading_error" else 4  # m/s, m, J/m: a few mm(/s) show
        print(f"{args.metric}, per terrain, B - A{unit} (A: {args.a}, B: {args.b})")
        print(f"{'group':>18} {'terrains':>8} {'A':>9} {'B':>9} {'B - A':>9} {'SE':>8}")
        for group, r in rows.items():
            verdict = ("resolved" if r["resolved"] else "not resolved") if r["terrains"] >= MIN_TERRAINS else \
                f"too few terrains (< {MIN_TERRAINS})"
            print(f"{group:>18} {r['terrains']:>8d} {scale * r['a']:>9.{digits}f} {scale * r['b']:>9.{digits}f} "
                  f"{scale * r['difference']:>+9.{digits}f} {scale * r['se']:>8.{digits}f}  {verdict}")

    run_command(parser.prog, show, args)


if __name__ == "__main__":
    main()
