# aacn-triage: slim Python base, non-root user, SQLite on a volume by default
# (deploy/compose.yaml runs replicas of this image on PostgreSQL behind nginx).
FROM python:3.11-slim

# The numba kernels are compiled at build time (below) for this CPU model, so that a
# replica loads them from the image's cache and is ready in seconds; numba keys its
# cache on the CPU it compiles for. "generic" (any x86-64, no AVX) holds on every
# host; an image that runs only on a known CPU model may name it (its LLVM name,
# e.g. --build-arg NUMBA_CPU_NAME=skylake-avx512) for faster kernels.
ARG NUMBA_CPU_NAME=generic

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    NUMBA_CPU_NAME=${NUMBA_CPU_NAME} \
    NUMBA_CACHE_DIR=/var/cache/aacn/numba \
    AACN_NUMBA_CACHE_DIR=/var/cache/aacn/numba \
    AACN_DATABASE_URL=sqlite:////data/aacn-triage.db \
    AACN_HOST=0.0.0.0 \
    AACN_PORT=8000 \
    AACN_SPOOL_PATH=/var/lib/aacn-spool/spool.db

RUN useradd --create-home --uid 10001 aacn \
    && mkdir -p /data /var/cache/aacn/numba /var/lib/aacn-spool \
    && chown -R aacn:aacn /data /var/cache/aacn /var/lib/aacn-spool

WORKDIR /app
COPY pyproject.toml README.md alembic.ini ./
COPY models ./models
COPY service ./service
COPY migrations ./migrations
RUN pip install .

USER aacn
# Warm-up: load and verify the models and compile every kernel of the request path
# into the cache, as `serve` does at start (service.context.engine_models_for ->
# models.triage.warm_up); a start then loads them (a few seconds) instead of
# compiling them (~20 s on 2 cores).
RUN python -c "from service.context import engine_models_for; from service.settings import get_settings; engine_models_for(get_settings())" \
    && test -n "$(ls -A /var/cache/aacn/numba)"

VOLUME ["/data", "/var/lib/aacn-spool"]
EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=5s --start-period=30s --retries=3 \
    CMD python -c "import urllib.request,sys; sys.exit(0 if urllib.request.urlopen('http://127.0.0.1:8000/livez', timeout=4).status == 200 else 1)"
CMD ["aacn-triage", "serve", "--host", "0.0.0.0"]
