"""Benchmark: validating a folder of 100 valid PXML documents.

Usage: python bench/validate.py

Reports the in-process time (schemas and parser already built, as when an
editor integration validates repeatedly) and the time of a cold
``prima validate`` process (imports and the one-off schema build included).
"""

from __future__ import annotations

import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from prima.dsl import collect, validate_paths

ROOT = Path(__file__).resolve().parents[1]
SOURCES = (sorted((ROOT / "apps").rglob("*.pxml"))
           + sorted((ROOT / "tests/dsl/data/valid").glob("*.pxml")))


def make_corpus(folder: Path, n: int = 100) -> list[Path]:
    for i in range(n):
        src = SOURCES[i % len(SOURCES)]
        shutil.copy(src, folder / f"doc{i:03d}-{src.name}")
    return collect([folder])


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        files = make_corpus(Path(tmp))
        lines = sum(len(f.read_text().splitlines()) for f, _named in files)
        report = validate_paths(files)  # warm up: build schemas and the parser once
        assert report.errors == 0, report.problems
        runs = []
        for _ in range(5):
            start = time.perf_counter()
            validate_paths(files)
            runs.append(time.perf_counter() - start)
        warm = statistics.median(runs)
        colds = []
        for _ in range(3):
            start = time.perf_counter()
            subprocess.run([sys.executable, "-m", "prima", "validate", tmp],
                           check=True, capture_output=True)
            colds.append(time.perf_counter() - start)
        cold = statistics.median(colds)
    print(f"{len(files)} documents, {lines} lines")
    print(f"in-process (warm): {warm * 1000:.0f} ms total, "
          f"{warm / len(files) * 1000:.2f} ms per document")
    print(f"prima validate (cold process): {cold * 1000:.0f} ms total")


if __name__ == "__main__":
    main()
