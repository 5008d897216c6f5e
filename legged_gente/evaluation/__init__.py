"""Evaluation: the gente100 benchmark (items, checker), rollouts with metrics, tasks and figures (docs/evaluation.md)."""
