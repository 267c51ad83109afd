"""Evaluation of the network inside the whole pipeline (paper Table I protocol, docs/evaluation.md) and of its
properties (multimodality, region-mask compliance, physical-property sensitivity). `mani-lab eval network`."""
