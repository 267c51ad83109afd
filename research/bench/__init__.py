"""Benchmarks of the service, the queue and gRPC (`mani-lab bench NAME`); the science's are in `research.commands`."""
