# The two set-up commands of the README. Both are idempotent: the venv is (re)installed only when
# pyproject.toml (or the client distribution's) changed since the last install.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp
HOST ?= 127.0.0.1
# HTTP's port; unset: 8000, or a free port printed at start when 8000 is taken (`make serve PORT=8080`)
PORT ?=
# gRPC's port; unset: 50051, or a free port printed at start when 50051 is taken (`make serve GRPC_PORT=50052`)
GRPC_PORT ?=

.PHONY: serve test test-slow lint install

$(STAMP): pyproject.toml distributions/client/pyproject.toml research/pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	# torch first, pinned: the CPU wheel on disk (an unpinned torch pulls a CUDA build).
	$(BIN)/python -m pip install -q torch==2.13.0
	# the client distribution from its folder in the same command: the server requires manifoundation-client
	# (same version), which no package index has to provide; the research tools (`mani-lab`) beside them.
	$(BIN)/python -m pip install -q -e distributions/client -e '.[dev]' -e research
	# A venv made before the split had `mani` from the server distribution: replacing that one removes the script
	# the client just wrote, so the client (which owns `mani` now) is written once more, without its dependencies.
	test -x $(BIN)/mani || $(BIN)/python -m pip install -q --no-deps --force-reinstall -e distributions/client
	# test data: third-party hands (pyproject's `third-party-hands`); only their description files are read,
	# so their own dependencies (numba, pinocchio, ...) are not installed.
	$(BIN)/python -m pip install -q --no-deps 'robosuite>=1.5,<1.6' 'orca-sim>=0.1,<0.2' 'robot-properties-fingers>=2,<3'
	# the science's compiled loops (numba), compiled once here rather than by the first request
	$(BIN)/python -m manifoundation.core.compiled
	touch $(STAMP)

install: $(STAMP)

serve: $(STAMP)
	$(BIN)/mani serve --host $(HOST) $(if $(PORT),--port $(PORT)) $(if $(GRPC_PORT),--grpc-port $(GRPC_PORT))

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/mypy

# two test processes, one per core: most tests wait on servers, subprocesses and sockets (serial: 5:01 wall for
# 3:28 of CPU on this machine's 2 cores; -n 2: 3:16)
test: lint
	$(BIN)/python -m pytest -n 2

test-slow: $(STAMP)
	$(BIN)/python -m pytest -m slow
