# Mesh Normal Calculator: `uvicorn app.main:app` on 0.0.0.0:8000, as a non-root user.
#
#   docker build -t mesh-normal-calculator .
#   docker run --rm -p 8000:8000 mesh-normal-calculator
#   docker run --rm --read-only --tmpfs /tmp -p 8000:8000 mesh-normal-calculator   # read-only root
#
# Nothing is written at run time: a read-only root works, with or without a tmpfs at /tmp.
#
# Two stages: the builder installs the locked runtime dependencies (uv.lock: the library's own and
# the `web` group) into /opt/venv, compiles the library's wheel (its C++ core, with g++) and
# installs it there; the final image gets that venv plus app/, templates/ and static/ in /app,
# and no compiler.

FROM python:3.11-slim AS builder

# Behind an intercepting HTTPS proxy, pass the CA bundle (these are plain env vars in RUN steps):
#   --build-arg SSL_CERT_FILE=... --build-arg PIP_CERT=... --build-arg UV_NATIVE_TLS=1
ARG SSL_CERT_FILE
ARG PIP_CERT
ARG UV_NATIVE_TLS
ARG UV_VERSION=0.13.9

ENV PIP_DISABLE_PIP_VERSION_CHECK=1 \
    UV_PYTHON_DOWNLOADS=never \
    UV_PROJECT_ENVIRONMENT=/opt/venv \
    UV_COMPILE_BYTECODE=1 \
    UV_LINK_MODE=copy \
    UV_NO_CACHE=1

# uv and the C++ compiler only live in the builder stage (CMake, Ninja and nanobind come from
# PyPI into the wheel's isolated build). Python's headers: the official image has them; a
# Debian-based stand-in may not.
# hadolint ignore=DL3008
RUN apt-get update \
    && apt-get install -y --no-install-recommends g++ \
    && (python3 -c 'import os, sys, sysconfig; sys.exit(not os.path.exists(os.path.join(sysconfig.get_paths()["include"], "Python.h")))' \
        || apt-get install -y --no-install-recommends python3-dev) \
    && rm -rf /var/lib/apt/lists/*
RUN python -m venv /opt/uv \
    && /opt/uv/bin/pip install --no-cache-dir "uv==${UV_VERSION}"

WORKDIR /app

# Dependencies first, from the lock file alone: this layer stays cached until
# pyproject.toml or uv.lock change. --frozen: exactly the locked versions;
# the `web` group only, so the `test` group (pytest, playwright, ...) is not installed.
COPY pyproject.toml uv.lock ./
RUN /opt/uv/bin/uv sync --frozen --no-default-groups --group web --no-install-project \
    --python python3

# The library itself, as a wheel: built in isolation (--no-config: the checkout's [tool.uv]
# settings are for its editable install) and installed into the same venv.
COPY README.md CMakeLists.txt ./
COPY cpp ./cpp
COPY mesh_normal ./mesh_normal
RUN /opt/uv/bin/uv build --no-config --wheel --out-dir /tmp/dist . \
    && /opt/uv/bin/uv pip install --python /opt/venv/bin/python --no-deps /tmp/dist/*.whl \
    && rm -rf /tmp/dist


FROM python:3.11-slim

ENV PATH=/opt/venv/bin:$PATH \
    PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1

RUN groupadd --gid 10001 app \
    && useradd --no-log-init --uid 10001 --gid app --no-create-home \
       --home-dir /nonexistent --shell /usr/sbin/nologin app

COPY --from=builder /opt/venv /opt/venv

# The app reads templates/ and static/ from the checkout's layout, so it runs from the source
# folder; uvicorn puts the working directory on sys.path (for app; mesh_normal is the installed
# wheel's, so no copy of its sources may be here to shadow it).
WORKDIR /app
COPY app ./app
COPY templates ./templates
COPY static ./static
RUN python -m compileall -q app \
    && python -m app.web.templating \
    && chmod -R a+rX,go-w templates/__pycache__

USER 10001:10001

EXPOSE 8000

HEALTHCHECK --interval=30s --timeout=5s --start-period=10s --retries=3 \
    CMD ["python", "-c", "import urllib.request; urllib.request.urlopen('http://127.0.0.1:8000/healthz', timeout=4)"]

# The server's limits (docs/operators.md): h11 caps a request's header at about
# 16 KB (httptools takes any size), idle keep-alive connections close after 5 s, more than 100
# connections at once get a 503, and a stop lets requests in flight finish for up to 8 s
# (within `docker stop`'s 10 s). Read timeouts for headers and bodies belong to the proxy in
# front. The same options are in the Makefile's `make run` (tests/app/test_server_limits.py).
CMD ["uvicorn", "app.main:app", "--host", "0.0.0.0", "--port", "8000", \
     "--http", "h11", "--h11-max-incomplete-event-size", "16384", \
     "--timeout-keep-alive", "5", "--limit-concurrency", "100", "--backlog", "256", \
     "--timeout-graceful-shutdown", "8"]
