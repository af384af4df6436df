# Flower from PyPI on percussim's image (which has Celery), in place of mher/flower: run as
# `celery flower`, configured by CELERY_BROKER_URL and FLOWER_* variables as that image is.
ARG PERCUSSIM_IMAGE=percussim:latest
FROM ${PERCUSSIM_IMAGE}
USER root
RUN pip install "flower>=2,<3"
USER percussim
CMD ["celery", "flower"]
# Flower's own page, in place of the API's check inherited from percussim's image.
HEALTHCHECK --interval=30s --timeout=5s --start-period=10s --retries=3 \
    CMD ["python", "-c", "import os, urllib.request; urllib.request.urlopen('http://127.0.0.1:' + os.environ.get('FLOWER_PORT', '5555') + '/healthcheck', timeout=4)"]
