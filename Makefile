# Two commands on a fresh machine: `make run` and `make test`. Both create the environment.
SHELL := /bin/bash
export UV_PYTHON_DOWNLOADS := never
export UV_NATIVE_TLS := 1
UV := $(shell command -v uv 2>/dev/null || echo .tools/bin/uv)
HOST ?= 127.0.0.1
PORT ?= 8000

.PHONY: run test lint bench env clean

# uv itself comes from PyPI when the machine does not have it yet.
.tools/bin/uv:
	python3 -m venv .tools
	.tools/bin/pip install --quiet uv

.venv/.installed: pyproject.toml uv.lock | $(UV)
	$(UV) sync --locked --extra test
	touch $@

env: .venv/.installed

run: env
	.venv/bin/uvicorn app.main:app --host $(HOST) --port $(PORT)

test: env
	.venv/bin/ruff check app tests benchmarks
	.venv/bin/pytest

bench: env
	.venv/bin/python -m benchmarks.run

clean:
	rm -rf .venv .tools .pytest_cache .hypothesis
