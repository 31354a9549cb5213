# Two commands on a fresh machine: `make run` and `make test`. Both create the environment.
SHELL := /bin/bash
export UV_PYTHON_DOWNLOADS := never
export UV_NATIVE_TLS := 1
# The environments hold compiled bytecode (site-packages, and the checkout's own mesh_normal/ and
# app/ below), written once here: a server or command that starts then reads it instead of
# compiling every module it imports (PYTHONDONTWRITEBYTECODE, often set, keeps Python from
# writing it later). With it, the first page comes nearly three times sooner.
export UV_COMPILE_BYTECODE := 1
UV := $(shell command -v uv 2>/dev/null || echo .tools/bin/uv)
# The environment's tools first: the editable install rebuilds the compiled core (cpp/) with the
# `build` group's CMake and Ninja when a C++ file changed.
export PATH := $(CURDIR)/.venv/bin:$(PATH)
HOST ?= 127.0.0.1
PORT ?= 8000

.PHONY: FORCE run test test-sanitize lint docs docs-serve bench bench-first bench-hostile bench-workers bench-mesh bench-mesh-e2e bench-readers bench-orient bench-points bench-soak bench-memory bench-startup bench-batch env clean vendor

# uv itself comes from PyPI when the machine does not have it yet.
.tools/bin/uv:
	python3 -m venv .tools
	.tools/bin/pip install --quiet uv

# Serving needs the library and the `web` group; testing adds the `test` group. Each target
# syncs the environment to exactly what it needs (uv is quick when nothing changed).
# The editable install maps each module of the library to its file, so a module added, moved or
# removed needs it redone: this list is rewritten only when the modules change, and it is one of
# uv's cache keys (pyproject.toml), so the next sync installs the library again.
MODULES = build/modules.txt
$(MODULES): FORCE
	@mkdir -p build && find mesh_normal -name '*.py' | sort > $@.new && \
		if cmp -s $@.new $@; then rm $@.new; else mv $@.new $@; fi
FORCE:

.venv/.web: pyproject.toml uv.lock $(MODULES) | $(UV)
	$(UV) sync --locked --group web
	$(COMPILE_SOURCES)
	rm -f .venv/.test && touch $@

.venv/.test: pyproject.toml uv.lock $(MODULES) | $(UV)
	$(UV) sync --locked --group test
	$(COMPILE_SOURCES)
	rm -f .venv/.web && touch $@

env: .venv/.test

# The checkout's own modules (installed editable, so uv does not compile them) and its page
# templates (app/web/templating.py); quick when the bytecode is current, and run again by
# `make run` since the sources change between runs.
COMPILE_SOURCES = .venv/bin/python -m compileall -q mesh_normal app && .venv/bin/python -m app.web.templating

# The server's limits, as in the Dockerfile's CMD (see docs/operators.md).
SERVER_LIMITS := --http h11 --h11-max-incomplete-event-size 16384 --timeout-keep-alive 5 \
	--limit-concurrency 100 --backlog 256 --timeout-graceful-shutdown 8

run: .venv/.web
	$(COMPILE_SOURCES)
	.venv/bin/uvicorn app.main:app --host $(HOST) --port $(PORT) $(SERVER_LIMITS)

# Importing the core rebuilds it if a C++ file changed, and with it the stubs mypy reads.
CORE = .venv/bin/python -c "import mesh_normal._core"

lint: .venv/.test
	$(CORE)
	.venv/bin/ruff format --check mesh_normal app tests benchmarks docs/hooks.py
	.venv/bin/ruff check mesh_normal app tests benchmarks docs/hooks.py
	.venv/bin/mypy

test: lint docs
	.venv/bin/pytest
	$(MAKE) test-sanitize

# The compiled core under AddressSanitizer and UndefinedBehaviorSanitizer, in an environment
# (.venv-asan) and build tree of its own: the file readers' tests, the hostile and mutated files,
# the kernels' tests. A sanitizer report ends the run with its stack. The sanitizer runtime is
# preloaded into Python, so only tests that start no browser run here.
SANITIZE := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all
SANITIZED_TESTS := tests/mesh_normal/files tests/mesh_normal/points \
	tests/mesh_normal/mesh/test_faces.py tests/mesh_normal/mesh/test_vertices.py \
	tests/mesh_normal/mesh/test_corners.py tests/mesh_normal/mesh/test_topology.py \
	tests/mesh_normal/mesh/test_orientation.py tests/mesh_normal/mesh/test_orientation_core.py \
	tests/mesh_normal/mesh/test_nesting.py tests/mesh_normal/mesh/test_visibility.py \
	tests/mesh_normal/test_no_harm.py tests/mesh_normal/mesh/test_checks.py
test-sanitize: .venv/.test
	UV_PROJECT_ENVIRONMENT=.venv-asan $(UV) sync --locked --group test \
		-C build-dir=build-asan -C cmake.build-type=RelWithDebInfo \
		-C "cmake.define.CMAKE_CXX_FLAGS=$(SANITIZE)" \
		-C "cmake.define.CMAKE_SHARED_LINKER_FLAGS=-fsanitize=address,undefined" \
		-C cmake.define.MESH_NORMAL_STUBS=OFF
	PATH="$(CURDIR)/.venv-asan/bin:$$PATH" \
	LD_PRELOAD="$$(gcc -print-file-name=libasan.so) $$(gcc -print-file-name=libubsan.so)" \
	ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1 \
		.venv-asan/bin/pytest --capture=sys -p no:randomly -p no:cacheprovider -q $(SANITIZED_TESTS)

# The documentation site (mkdocs.yml, docs/): built strictly, so that a broken link or a missing
# reference fails; `make docs-serve` previews it at http://127.0.0.1:8001 as it is edited.
export NO_MKDOCS_2_WARNING := 1
docs: .venv/.test
	.venv/bin/mkdocs build --strict --quiet

docs-serve: .venv/.test
	.venv/bin/mkdocs serve --dev-addr 127.0.0.1:8001

# Every benchmark, each writing its table to docs/benchmarks/NAME.md for docs/benchmarks.md
# (hours; needs wrk, Chromium and hyperfine). The bench-* targets below run one each and print.
bench: .venv/.test
	$(UV) sync --locked --group test --group bench
	$(COMPILE_SOURCES)
	.venv/bin/python -m benchmarks.run --rounds 5 --loads 7 --markdown docs/benchmarks/api.md
	.venv/bin/python -m benchmarks.startup --rounds 7 --runs 3 --markdown docs/benchmarks/startup.md
	.venv/bin/python -m benchmarks.first_answer $(if $(MESH),--mesh $(MESH)) --markdown docs/benchmarks/first-answer.md
	.venv/bin/python -m benchmarks.mesh_kernels --sizes 871414 14000000 --idle 7 --markdown docs/benchmarks/mesh-kernels.md
	.venv/bin/python -m benchmarks.orientation --markdown docs/benchmarks/orientation.md
	.venv/bin/python -m benchmarks.readers --markdown docs/benchmarks/readers.md
	.venv/bin/python -m benchmarks.mesh_end_to_end --sizes 871414 --lucy-runs 1 --skip-readers --markdown docs/benchmarks/mesh-end-to-end.md
	.venv/bin/python -m benchmarks.memory --markdown docs/benchmarks/memory.md
	.venv/bin/python -m benchmarks.points --markdown docs/benchmarks/points.md
	.venv/bin/python -m benchmarks.batch --markdown docs/benchmarks/batch.md
	.venv/bin/python -m benchmarks.stalls --markdown docs/benchmarks/stalls.md
	.venv/bin/python -m benchmarks.hostile --markdown docs/benchmarks/hostile.md
	.venv/bin/python -m benchmarks.workers --markdown docs/benchmarks/workers.md
	.venv/bin/python -m benchmarks.soak --markdown docs/benchmarks/soak.md

bench-mesh: .venv/.test
	$(UV) sync --locked --group test --group bench
	.venv/bin/python -m benchmarks.mesh_kernels

bench-soak: .venv/.test
	.venv/bin/python -m benchmarks.soak

bench-orient: .venv/.test
	.venv/bin/python -m benchmarks.orientation

# Point-cloud normals against Open3D (in the test group); ARGS=--quick for a fifth of the sizes.
bench-points: .venv/.test
	.venv/bin/python -m benchmarks.points $(ARGS)

# The batch on small STL files: 1 vs 2 local workers, per-file overhead; ARGS="--files 100".
bench-batch: .venv/.test
	.venv/bin/python -m benchmarks.batch $(ARGS)

# The hostile uploads (tests/data/hostile/ and larger generated ones) against a real server.
bench-hostile: .venv/.test
	.venv/bin/python -m benchmarks.hostile $(ARGS)

# The worker processes: a start, the next job after a killed one, the server's stop.
bench-workers: .venv/.test
	.venv/bin/python -m benchmarks.workers $(ARGS)

bench-memory: .venv/.test
	.venv/bin/python -m benchmarks.memory

# The command line's and the server's start, against a bare FastAPI app (needs hyperfine).
# The first answer from a fresh environment, beside trimesh (MESH=path/to/bunny.obj; see
# docs/benchmarks.md for the file).
bench-first: .venv/.test
	.venv/bin/python -m benchmarks.first_answer $(if $(MESH),--mesh $(MESH)) $(ARGS)

bench-startup: .venv/.test
	$(COMPILE_SOURCES)
	.venv/bin/python -m benchmarks.startup $(ARGS)

bench-readers: .venv/.test
	$(UV) sync --locked --group test --group bench
	.venv/bin/python -m benchmarks.readers $(ARGS)

bench-mesh-e2e: .venv/.test
	$(UV) sync --locked --group test --group bench
	.venv/bin/python -m benchmarks.mesh_end_to_end

clean:
	rm -rf .venv .venv-asan build build-asan .tools .pytest_cache .hypothesis mesh_normal/_core.pyi

# Refresh the vendored front-end files from the npm registry (see static/vendor/README.md).
PLOTLY_VERSION := 4.1.1
SWAGGER_UI_VERSION := 5.35.0
vendor:
	rm -rf .vendor-tmp && mkdir .vendor-tmp
	cd .vendor-tmp && npm pack --silent plotly.js-basic-dist-min@$(PLOTLY_VERSION) \
		plotly.js-gl3d-dist-min@$(PLOTLY_VERSION) swagger-ui-dist@$(SWAGGER_UI_VERSION)
	tar -xzf .vendor-tmp/plotly.js-basic-dist-min-$(PLOTLY_VERSION).tgz -C .vendor-tmp
	cp .vendor-tmp/package/plotly-basic.min.js .vendor-tmp/package/LICENSE static/vendor/plotly/
	rm -rf .vendor-tmp/package
	tar -xzf .vendor-tmp/plotly.js-gl3d-dist-min-$(PLOTLY_VERSION).tgz -C .vendor-tmp
	cp .vendor-tmp/package/plotly-gl3d.min.js static/vendor/plotly/
	rm -rf .vendor-tmp/package
	tar -xzf .vendor-tmp/swagger-ui-dist-$(SWAGGER_UI_VERSION).tgz -C .vendor-tmp
	cd .vendor-tmp/package && cp swagger-ui-bundle.js swagger-ui.css LICENSE NOTICE favicon-32x32.png ../../static/vendor/swagger-ui/
	rm -rf .vendor-tmp
