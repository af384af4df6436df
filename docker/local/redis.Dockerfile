# percussim-redis:local (scripts/local-images): Debian's redis-server in place of redis:7-alpine.
# Its data folder and command are those of the public image, so docker-compose.yml's command,
# volume and health check apply unchanged.
FROM percussim-base:local
RUN apt-get update \
    && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends redis-server \
    && rm -rf /var/lib/apt/lists/*
WORKDIR /data
CMD ["redis-server"]
