"""The package is described in pyproject.toml; this file only adds, when asked, the
compiled build: with ``PRIMA_MYPYC=1`` the hot modules of the simulator, the mediator,
the interpreter and the judge are compiled to C extensions by mypyc (part of mypy), for
sweeps and checks of many runs. Every trace is the same as the pure Python build's.
mypyc type-checks what it compiles, so it needs mypy, lxml's stubs and PRIMA's own
dependencies where it builds: build_backend.py asks pip for them, so one command does it
(with a C compiler and Python's headers on the machine):

    PRIMA_MYPYC=1 python -m pip install .

In an environment that has them (mypy: the lint extra), ``PRIMA_MYPYC=1 python setup.py
build_ext --inplace`` builds it in place (bench/_measure.py's compiled_copy). Not with ``-e``: an editable install puts the compiled modules beside the sources,
where they hide later changes to them. Without ``PRIMA_MYPYC`` (the default, and what
the tests run) nothing is compiled.
docs/judging.md (Many runs) says when to use it; docs/benchmarks.md (Sweeps), what it
gains and how it is held to the pure build's traces.
"""

from __future__ import annotations

import os

from setuptools import setup

COMPILED = [
    "prima/sim/_kernel.py",
    "prima/sim/_world.py",
    "prima/sim/_simulator.py",
    "prima/sim/_user.py",
    "prima/sim/_behaviors.py",
    "prima/sim/_maps.py",
    "prima/sim/_records.py",
    "prima/sim/_spec.py",
    "prima/mediator/_config.py",
    "prima/mediator/_fairness.py",
    "prima/mediator/_holds.py",
    "prima/mediator/_index.py",
    "prima/mediator/_intake.py",
    "prima/mediator/_interface.py",
    "prima/mediator/_log.py",
    "prima/mediator/_mediator.py",
    "prima/mediator/_memory.py",
    "prima/mediator/_policies.py",
    "prima/mediator/_ranking.py",
    "prima/mediator/_rounds.py",
    "prima/mediator/_state.py",
    "prima/interpreter/_interpreter.py",
    "prima/dsl/_model.py",
    "prima/dsl/_fastparse.py",
    "prima/dsl/_commands.py",
    "prima/dsl/_loader.py",
    "prima/dsl/_profile.py",
    "prima/judge/_context.py",
    "prima/judge/_findings.py",
    "prima/judge/_judging.py",
    "prima/judge/_measures.py",
    "prima/judge/_reactions.py",
    "prima/judge/_thresholds.py",
    "prima/scenario/_file.py",
    "prima/scenario/_setup.py",
    "prima/catalog.py",
    "prima/record.py",
    "prima/run.py",
    "prima/trace.py",
    "prima/xmlio.py",
]
"""What the compiled build compiles: where a run spends its time, from the simulator's
steps to the judge's measures and the lines of the trace; the records they read (the
catalog's Commands, calls and outcomes, poses, the robot's figures: read from compiled
code, a compiled class's field is a C read, an interpreted one's a lookup by name), and
a run's setting up (its scenario read and checked). ``record.py`` with them: the
catalog's records derive from its ``Record``."""

ext_modules = []
if os.environ.get("PRIMA_MYPYC") == "1":
    from mypyc.build import mypycify

    ext_modules = mypycify(COMPILED, opt_level="3")

setup(ext_modules=ext_modules)
