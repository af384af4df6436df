"""The docker-compose deployment's times: the local base images, the image build (cold and
cached) and the stack's start, as tests/test_compose.py builds and starts it (the base images
from scripts/local-images, every service on the host's network on loopback ports).

    .venv/bin/python bench/deploy.py [--remake-base] [--repeat 3]

Needs a running dockerd (scripts/test starts one). Figures in docs/deploy.md.

1. scripts/local-images: with --remake-base, percussim-base:local is removed first and made again
   (debootstrap); otherwise the time to find it and rebuild Redis's and PostgreSQL's from cache.
2. The image build with no layer cache (every dependency downloaded and installed, the kernel
   compiled), then with a change to the solver's code (a file added to it for the build, so the
   dependencies come from cache and the kernel is compiled again), with that change undone (a
   change again: the image a build replaces is removed, its layers with it), with nothing
   changed, and with a change to pyproject.toml outside the image's dependencies (a comment: the
   dependencies come from cache, percussim is installed and its kernel compiled again).
3. `compose up` of the API, two workers, Redis, PostgreSQL and Flower until /readyz lists both
   workers, then `compose down -v`: each --repeat times.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from percussim.testing.compose_stack import ComposeStack, docker, local_images, require_docker

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--remake-base", action="store_true", help="make percussim-base:local again (debootstrap)")
    parser.add_argument("--repeat", type=int, default=3, help="stack starts to time")
    args = parser.parse_args()
    require_docker()
    if args.remake_base:
        for name in ("percussim-postgres:local", "percussim-redis:local", "percussim-base:local"):
            docker("rmi", name, check=False)
    print(f"scripts/local-images{' (base made again)' if args.remake_base else ''}: {local_images():.1f} s")

    stack = ComposeStack()
    print(f"image build, no layer cache: {stack.build(no_cache=True):.1f} s")
    change = ROOT / "solver" / "_bench_change.py"
    change.write_text('"""A change to the solver\'s code, made by bench/deploy.py for one build."""\n')
    try:
        print(f"image build, a change to the solver's code: {stack.build():.1f} s")
    finally:
        change.unlink()
    print(f"image build, that change undone: {stack.build():.1f} s")
    print(f"image build, nothing changed: {stack.build():.1f} s")
    pyproject = ROOT / "pyproject.toml"
    kept = pyproject.read_text()
    pyproject.write_text(kept + "# a change by bench/deploy.py for one build\n")
    try:
        print(f"image build, a comment added to pyproject.toml: {stack.build():.1f} s")
    finally:
        pyproject.write_text(kept)
    stack.down()

    starts, downs = [], []
    for _ in range(args.repeat):
        stack = ComposeStack()
        try:
            starts.append(stack.up())
        finally:
            start = time.monotonic()
            stack.down()
            downs.append(time.monotonic() - start)
    for what, values in (("compose up to /readyz with 2 workers", starts), ("compose down -v", downs)):
        print(f"{what}: median {statistics.median(values):.1f} s (min {min(values):.1f}, max {max(values):.1f})")
    size = int(docker("image", "inspect", "--format", "{{.Size}}", "percussim:test"))
    print(f"image size: {size / 1e6:.0f} MB")


if __name__ == "__main__":
    main()
