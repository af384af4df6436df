# percussim-postgres:local (scripts/local-images): Debian's PostgreSQL in place of
# postgres:16-alpine, with the public image's conventions docker-compose.yml relies on: data in
# /var/lib/postgresql/data, a new cluster set up from POSTGRES_USER, POSTGRES_PASSWORD and
# POSTGRES_DB, and pg_isready on the PATH.
FROM percussim-base:local
RUN apt-get update \
    && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends postgresql \
    && rm -rf /var/lib/apt/lists/* \
    && pg_dropcluster "$(ls /usr/lib/postgresql)" main \
    && ln -s /usr/lib/postgresql/*/bin /usr/lib/postgresql/bin
ENV PATH=/usr/lib/postgresql/bin:$PATH \
    PGDATA=/var/lib/postgresql/data
COPY postgres-entrypoint /usr/local/bin/
VOLUME /var/lib/postgresql/data
ENTRYPOINT ["postgres-entrypoint"]
CMD ["postgres"]
