"""The lab: the science's offline commands (`mani hands`, `data`, `train`, `eval`, `plan` and the science's
benchmarks). Each module has ``register(subparsers)`` and imports its heavy dependencies when its command runs.

Above `models` (it drives the science and prints tables and progress bars, which the pure science must not) and
beside the service: nothing in the product imports it; `mani` finds its commands through entry points.
"""
