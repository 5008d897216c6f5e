"""Ship a run's checkpoint as the package's pretrained policy of a task (resources/policies/<task>/), for
`gente-play --pretrained` and `gente-evaluate --pretrained`.

    python tools/ship_policy.py logs/gente_biped_flat/<run>/model_1500.pt --task gente_biped_flat \
        --note "4096 envs, 1500 iterations on one GPU"
"""

import argparse

from legged_gente.utils.args import Parser, run_command
from legged_gente.utils.checkpoints import ship_policy


def ship(args: argparse.Namespace):
    from legged_gente.envs.task_registry import task_registry

    task_registry.get_cfgs(args.task)  # a registered task (its name becomes the package's policy folder)
    return ship_policy(args.checkpoint, args.task, args.note)


def main(argv=None) -> None:
    parser = Parser(prog="ship_policy", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("checkpoint", help="model_<iteration>.pt of a run (its config.json is read beside it)")
    parser.add_argument("--task", required=True, help="the task it was trained on")
    parser.add_argument("--note", required=True, help="how it was trained (stored in its config.json)")
    args = parser.parse_args(argv)
    print(f"wrote {run_command(parser.prog, ship, args)}")


if __name__ == "__main__":
    main()
