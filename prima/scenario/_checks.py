"""A scenario's checks beyond its own file: every file it names (its map, its robot
profile, its applications against that profile), each of the right kind and each
application in the slot it fits, and the places the applications name on its map.

One function makes the validation every reader of scenarios uses
(:func:`make_validation`): ``prima validate``, ``prima lsp`` (an editor's buffer),
and ``prima run`` and ``prima sweep`` when a scenario does not load
(:func:`checked_load`), so that the same bad scenario gives the same problems at the
same places from all of them.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

from prima.errors import DocumentError, LocatedError, Problem, ScenarioError, Severity

if TYPE_CHECKING:
    from prima.dsl import Checker, Header, RobotProfile, Validation
    from prima.sim import WorldMap

_T = TypeVar("_T")

__all__ = ["check_scenario", "checked_load", "make_validation", "scenario_checkers",
           "scenario_problems"]


def _problems(load: Callable[[Path], object], path: Path) -> list[Problem]:
    try:
        load(path)
    except LocatedError as exc:
        return list(exc.problems)
    return []


def scenario_checkers(validation: Validation, robot: bool) -> dict[str, Checker]:
    """The checkers of scenario and map files, by root namespace, for ``validation``.

    A scenario's check also checks every file it names, each once in the whole
    validation: its map, its robot profile, and its FA, EA and zone EAs against
    that profile (``robot``: the ``--robot`` profile instead, as ``prima run``
    does), and that each names the right kind of file and each application
    fits its slot. The simulator is imported only when a file of neither
    PRIMA's documents nor its robot profiles is met.
    """
    from prima.dsl import unknown_places
    from prima.scenario._file import MAP_NS, SCENARIO_NS, late_inputs, load_map, load_scenario

    maps: dict[Path, WorldMap] = {}
    """The maps checked without errors, by resolved path."""
    placed: set[tuple[Path, Path]] = set()
    """(document, map) pairs whose places were checked: each pair once."""

    def check_map(path: Path) -> list[Problem]:
        try:
            maps[path.resolve()] = load_map(path)
        except LocatedError as exc:
            return list(exc.problems)
        return []

    def check_places(map_path: Path, documents: Iterable[Path]) -> list[Problem]:
        world = maps.get(map_path.resolve())
        out: list[Problem] = []
        for document in documents:
            checked = validation.places(document)
            pair = (document.resolve(), map_path.resolve())
            if world is not None and checked is not None and pair not in placed:
                placed.add(pair)
                out.extend(unknown_places(*checked, [p.name for p in world.places],
                                          world.name, world.source))
        return out

    def check_scenario(path: Path) -> list[Problem]:
        # problems loading the scenario found in its map are the map's own check's
        problems = _problems(load_scenario, path)
        own = [p for p in problems if Path(p.file).resolve() == path.resolve()]
        own += late_inputs(path) if not problems else []
        return own + _check_named(validation, path, robot, MAP_NS, check_places)

    return {SCENARIO_NS: check_scenario, MAP_NS: check_map}


_SLOTS = {"fa": "fa", "ea": "ea", "zone": "ea"}
"""A scenario's reference role -> the kind of application that runs there."""


def _check_named(validation: Validation, scenario: Path, robot: bool, map_ns: str,
                 check_places: Callable[[Path, Iterable[Path]], list[Problem]]) -> list[Problem]:
    """Check the files ``scenario`` names; the problems of the scenario itself (a file of
    the wrong kind, an application in the wrong slot, two applications of one name) are
    returned, located at the attribute that names the file, and then, located in the
    applications, each place they name that the scenario's map lacks (``check_places``)."""
    from prima.dsl import NAMESPACE as PXML_NS
    from prima.dsl import ROBOT_NAMESPACE as ROBOT_NS
    from prima.scenario._file import scenario_references

    expected = {"map": (map_ns, "map"), "profile": (ROBOT_NS, "robot profile")}
    out: list[Problem] = []
    refs = []
    for ref in scenario_references(scenario):
        if not ref.path.is_file():  # the scenario's own check says it is not found
            continue
        namespace, what = expected.get(ref.role, (PXML_NS, "PXML document"))
        found = _namespace(ref.path)
        if found is not None and found != namespace:
            out.append(Problem(str(scenario), ref.line, ref.col, Severity.ERROR,
                               f"'{ref.value}' is not a {what} (its root is in {found!r})"))
        else:
            refs.append(ref)
    profile = validation.profile
    for ref in refs:
        if ref.role == "map":
            validation.add(ref.path)
        elif ref.role == "profile":
            named = validation.robot(ref.path)
            profile = profile if robot else named
    if profile is None:  # the named profile has errors: its documents wait until it is fixed
        return out
    fa_name: str | None = None
    eas: dict[str, tuple[str, Path]] = {}
    """The EAs running from the start: name -> the path as written, and the file."""
    for ref in (r for r in refs if r.role in _SLOTS):
        header = validation.document(ref.path, profile)
        message = None if header is None else _slot_fault(ref.role, ref.value, header, fa_name)
        name = "" if header is None else header.name
        earlier = eas.get(name) if header is not None and ref.role == "ea" else None
        # (one file named twice: the scenario's own check says so, once)
        if not message and earlier is not None and earlier[1] != ref.path.resolve():
            message = (f"the EAs '{earlier[0]}' and '{ref.value}' are both named '{name}'; "
                       "each application needs a name of its own")
        if message:
            out.append(Problem(str(scenario), ref.line, ref.col, Severity.ERROR, message))
        elif header is not None and ref.role == "fa":
            fa_name = header.name
        elif header is not None and ref.role == "ea":
            eas.setdefault(header.name, (ref.value, ref.path.resolve()))
    for map_ref in (r for r in refs if r.role == "map"):
        out.extend(check_places(map_ref.path, (r.path for r in refs if r.role in _SLOTS)))
    return out


def _namespace(path: Path) -> str | None:
    """The namespace of a file's root element, or None if it cannot be read or parsed."""
    from prima.dsl import root_namespace
    from prima.xmlio import read_source

    try:
        return root_namespace(read_source(path, DocumentError))
    except DocumentError:
        return None


def _slot_fault(role: str, written: str, header: Header, fa_name: str | None) -> str | None:
    """What ``prima run`` would refuse about this application in this slot, if anything."""
    slot = _SLOTS[role]
    if header.kind in _SLOTS.values() and header.kind != slot:
        return (f"'{written}' is an {header.kind.upper()} (kind=\"{header.kind}\"); "
                f"it cannot run as the {slot.upper()}")
    if role != "fa" and header.name == fa_name:
        whose = "the EA" if role == "ea" else "this zone's EA"
        return (f"the FA and {whose} are both named '{header.name}'; each application "
                "needs a name of its own")
    return None


def make_validation(profile: RobotProfile, *, robot: bool = False) -> Validation:
    """A validation as ``prima validate`` makes one: documents and robot profiles, and
    scenarios and maps with every file they name (``robot``: every document is checked
    against ``profile``, as ``--robot`` asks, not the scenario's robot nor the one its
    ``robot`` attribute names). ``prima lsp`` checks an editor's buffer with it."""
    from prima.dsl import Validation

    made: Validation = Validation(profile, follow_declared=not robot,
                                  more_checkers=lambda: scenario_checkers(made, robot))
    return made


def scenario_problems(scenario: str | Path, robot: str | Path | None = None) -> list[Problem]:
    """The problems of ``scenario`` and of every file it names, as ``prima validate
    SCENARIO`` reports them (``robot``: as ``--robot ROBOT`` does): its validation
    (:func:`make_validation`), in the order it finds them. Raises DocumentError for a
    ``robot`` profile that cannot be loaded."""
    from prima.collecting import fewer_collections
    from prima.dsl import default_profile, load_profile

    profile = load_profile(robot) if robot else default_profile()
    with fewer_collections():
        report = make_validation(profile, robot=robot is not None).run([Path(scenario)])
    return list(report.problems)


def check_scenario(scenario: str | Path, robot: str | Path | None = None) -> None:
    """Raise ScenarioError with the problems :func:`scenario_problems` finds, errors
    first, when one of them is an error: what ``prima run`` and ``prima sweep`` say of a
    scenario that does not load (:func:`checked_load`), the lines ``prima validate`` and
    ``prima lsp`` give for it."""
    problems = scenario_problems(scenario, robot)
    if any(p.severity is Severity.ERROR for p in problems):
        raise ScenarioError(sorted(problems, key=lambda p: p.severity is not Severity.ERROR))


def checked_load(scenario: str | Path, robot: str | Path | None, load: Callable[[], _T], *,
                 swapped: bool = False) -> _T:
    """``load()`` (a run made ready from ``scenario``); when it fails on a bad file, the
    scenario's validation (:func:`check_scenario`) says what is wrong, as ``prima
    validate`` and ``prima lsp`` do, if it finds an error, else the load's own error
    stands. A scenario that loads costs no second reading. ``swapped``: the command line
    swaps its FA or EA, so the scenario's own do not run and are not what is said (the
    documents that run are checked as they load)."""
    try:
        return load()
    except LocatedError:
        if not swapped:
            check_scenario(scenario, robot)
        raise
