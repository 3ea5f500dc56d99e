# aacn-triage: slim Python base, non-root user, SQLite on a volume by default.
FROM python:3.11-slim

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
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
VOLUME ["/data", "/var/lib/aacn-spool"]
EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=5s --start-period=30s --retries=3 \
    CMD python -c "import urllib.request,sys; sys.exit(0 if urllib.request.urlopen('http://127.0.0.1:8000/livez', timeout=4).status == 200 else 1)"
CMD ["aacn-triage", "serve", "--host", "0.0.0.0"]
