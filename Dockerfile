# One image for the API and the workers; the compose file picks the command.
FROM python:3.11-slim

ENV PYTHONDONTWRITEBYTECODE=1 PYTHONUNBUFFERED=1 PIP_NO_CACHE_DIR=1
WORKDIR /app

COPY pyproject.toml README.md ./
COPY distributions ./distributions
COPY manifoundation ./manifoundation

# torch pinned first; the client distribution (which the server requires) from its folder, in the same command.
# Point TORCH_INDEX_URL at a CPU wheel index for a small image (the default index
# serves a multi-GB CUDA build).
ARG TORCH_INDEX_URL=""
RUN pip install ${TORCH_INDEX_URL:+--index-url "$TORCH_INDEX_URL"} torch==2.13.0 \
    && pip install ./distributions/client .

RUN useradd --create-home mani
USER mani
EXPOSE 8000
CMD ["mani", "serve", "--host", "0.0.0.0", "--port", "8000"]
