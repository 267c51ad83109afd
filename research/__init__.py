"""Research: data generation, training, evaluation, the independent audit and every benchmark (`mani-lab`).

Never part of a product wheel; the served path imports nothing from here (tests/test_layering.py).
"""
