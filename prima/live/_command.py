"""``prima live``'s work, apart from its command line: make the session's base scenario,
serve the session until Ctrl-C (or SIGTERM), and say in one line how it ended."""

from __future__ import annotations

import asyncio
import ipaddress
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

from prima.errors import DocumentError, PrimaError, Problem, Severity
from prima.escape import shown_path
from prima.live._scenario import Base, for_apps, from_scenario, user_spot
from prima.run import Switches

__all__ = ["Options", "base_of", "serve"]


@dataclass(frozen=True)
class Options:
    """What the command line asked for, once checked."""

    inputs: tuple[Path, ...]
    """A scenario, or applications' documents."""
    switches: Switches = Switches()
    seed: int | None = None
    until: float = 3600.0
    speed: float = 1.0
    script: bool = False
    host: str = "127.0.0.1"
    port: int = 8400
    foxglove: int | None = None
    """The port of Foxglove's server, if one is asked for."""
    maps: Path | None = None
    """Where to find a map for applications alone (the shipped maps)."""
    map_file: Path | None = None
    robot: Path | None = None
    autoplay: bool = True


def base_of(options: Options) -> Base:
    """The session's base scenario; raises the inputs' located errors."""
    first = options.inputs[0]
    if first.suffix == ".xml":
        from prima.scenario import load_scenario

        loaded = load_scenario(first)
        spot = user_spot(loaded.map, loaded.robot.x, loaded.robot.y, loaded.robot.heading)
        return from_scenario(first, options.switches, seed=options.seed, script=options.script,
                             user_at=spot)
    return _apps_base(options)


def _apps_base(options: Options) -> Base:
    from prima.check import destinations, map_for, sends, starts
    from prima.dsl import default_profile, load_document, load_profile
    from prima.scenario import load_map

    profile = load_profile(options.robot) if options.robot else default_profile()
    documents = [(path, load_document(path, profile)) for path in options.inputs]
    fas = [p for p, d in documents if d.kind.value == "fa"]
    if len(fas) > 1:
        raise DocumentError([Problem(str(fas[1]), 1, 1, Severity.ERROR,
                                     f"a second FA ({fas[0].name} is one): a robot runs one")])
    if options.map_file is not None:
        maps = [(options.map_file, load_map(options.map_file))]
    else:
        folder = options.maps
        maps = [(p, load_map(p)) for p in sorted(folder.glob("*.xml"))] if folder else []
    world = next((m for m in maps if all(map_for(d, [m]) for _p, d in documents)), None)
    if world is None:
        named = sorted({place for _path, d in documents for where in destinations(d)
                        for place in where.places or ()})
        where = (f"in {shown_path(options.map_file)}" if options.map_file
                 else f"among the maps in {shown_path(options.maps)}" if options.maps
                 else "(no maps are installed: give one with --map)")
        raise PrimaError(f"no map has every place the applications name ({', '.join(named)}) "
                         f"{where}")
    replies = list(dict.fromkeys(s.to for _p, d in documents for s in sends(d)))
    return for_apps(documents, world, options.robot, options.seed, starts(world[1]), replies)


def _loopback(host: str) -> bool:
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return host == "localhost"


def serve(options: Options, base: Base, save: object, out: TextIO, err: TextIO) -> int:
    """Serve the session until Ctrl-C or SIGTERM (``save``: a :class:`SaveTo`)."""
    from prima.live._foxglove import FoxgloveLive
    from prima.live._judging import LiveJudge
    from prima.live._server import Hints, SaveTo, Server
    from prima.live._session import Session

    assert isinstance(save, SaveTo)
    if not _loopback(options.host):
        print(f"prima live: warning: serving on {options.host}: anyone who can reach it can "
              "act in the session and save it", file=err, flush=True)
    # The run's thread does a little every tenth of a simulated second; the judge and the
    # timeline, in another thread, a lot at once: threads take turns every millisecond
    # (not Python's 5), so the run never waits long behind them.
    sys.setswitchinterval(0.001)
    with tempfile.TemporaryDirectory(prefix="prima-live-") as scratch:
        fox: FoxgloveLive | None = None
        session = Session(base, Path(scratch), until=options.until, speed=options.speed)
        if options.foxglove is not None:
            fox = FoxgloveLive(session.world, host=options.host, port=options.foxglove,
                               robot_radius=session.run.profile.radius)
            session.tee = fox.line
        hints = Hints.of(session.run.documents(),
                         f"ws://{options.host}:{fox.port}" if fox else "")
        server = Server(session, title=base.name, host=options.host, port=options.port,
                        save=save, hints=hints, autoplay=options.autoplay,
                        layout=fox.layout() if fox else None, judge=LiveJudge(),
                        on_findings=fox.findings if fox else None)
        apps = ", ".join(session.run.app_names()) or "no applications"

        def ready(url: str) -> None:
            print(f"prima live: {url} ({base.name}: {apps}; {options.speed:g}x; Ctrl-C ends "
                  "it)", file=out, flush=True)
            if fox is not None:
                print(f"prima live: Foxglove: ws://{options.host}:{fox.port} (its layout: "
                      f"{url}foxglove-layout.json)", file=out, flush=True)

        try:
            asyncio.run(server.serve(ready))
        except KeyboardInterrupt:
            pass
        except OSError as exc:  # (the port is taken, say)
            raise PrimaError(f"cannot serve on {options.host}:{options.port}: "
                             f"{exc.strerror or exc}") from exc
        finally:
            session.stop()
            if fox is not None:
                fox.stop()
        saves = f"saved {server.saves} time(s)" if server.saves else "not saved"
        print(f"prima live: stopped at {session.reached():.2f} s of simulated time "
              f"({session.state}); {len(session.added)} input(s); {saves}", file=err,
              flush=True)
    return 0

