"""The mediator decides the same whatever ``PYTHONHASHSEED`` is.

String hashing is salted per process, so iterating a set of names (or device
names) gives a different order in each process. A decision whose order came
from such a set would make traces differ between runs; seed 1430 of the random
driver once did (two apps' budget decisions at one instant), and seed 15546
(the connect-channel policy asked the robot about a set of devices in set order,
and the scripted robot's answers depend on how often it is asked). Each random seed
is played in processes with different hash seeds, and every decision must
match.
"""

from __future__ import annotations

import os
import subprocess
import sys

SEEDS = (1430, 5003, 13385, 13478, 15546, 0, 7)
HASH_SEEDS = ("0", "1", "2", "3", "4", "5")

_PLAY = """
import hashlib, sys
from prima.mediator.random_driver import _Run, scenario
for seed in map(int, sys.argv[1:]):
    run = _Run(scenario(seed), 1e-6)
    run.play()
    h = hashlib.sha256()
    for d in run.h.decisions:
        h.update(repr(tuple(d)).encode())
    for ab in run.h.driver.started:
        h.update(repr((ab.id, ab.calls, sorted(ab.devices), sorted(ab.blended))).encode())
    print(seed, len(run.h.decisions), h.hexdigest())
"""


def _digests(hash_seed: str) -> str:
    env = {**os.environ, "PYTHONHASHSEED": hash_seed}
    done = subprocess.run([sys.executable, "-c", _PLAY, *map(str, SEEDS)], env=env,
                          capture_output=True, text=True, check=True)
    return done.stdout


def test_decisions_do_not_depend_on_the_hash_seed() -> None:
    first, *others = (_digests(h) for h in HASH_SEEDS)
    assert first.count("\n") == len(SEEDS)
    for hash_seed, out in zip(HASH_SEEDS[1:], others, strict=True):
        assert out == first, f"PYTHONHASHSEED={hash_seed} decides otherwise"
