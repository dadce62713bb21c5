"""A scenario made ready to run (:class:`Setup`): the scenario loaded, its robot profile,
the Commands it offers, the documents that run from the start (each checked in its slot
and against the map), every mediation policy layered (defaults, profile, scenario, the
caller) and mapped once into the mediator's configuration and the simulator's switches.

:class:`~prima.run.Run` takes a Setup and wires the parts; :class:`Loaded` keeps the
files a sweep's runs share.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from prima.catalog import Catalog
from prima.dsl import Document, RobotProfile, default_profile, load_document, load_profile, \
    unknown_places
from prima.errors import DocumentError, Problem, Severity
from prima.mediator import MediatorConfig
from prima.scenario._file import Scenario, load_map, load_scenario
from prima.sim import RobotSpec, WorldMap
from prima.vocab import POLICIES, AppKind, policy_settings

__all__ = ["Loaded", "Setup", "Switches", "check_slot", "checked", "mediator_config",
           "spec_from_profile"]


def check_slot(document: Document, role: AppKind) -> Document:
    """An FA document runs as the FA, an EA document as the EA."""
    if document.kind is not role:
        kind = document.kind
        raise DocumentError([Problem(document.path, 1, 1, Severity.ERROR,
                                     f"this is an {kind.name} (kind=\"{kind.value}\"); "
                                     f"it cannot run as the {role.name}")])
    return document


def spec_from_profile(profile: RobotProfile) -> RobotSpec:
    """The simulator's physical figures for a robot hardware profile."""
    return RobotSpec(
        radius=profile.radius, max_speed=profile.max_speed, max_accel=profile.max_accel,
        max_turn_rate=profile.max_turn_rate, speech_rate=profile.speech_rate,
        camera_fov=profile.camera_fov, camera_range=profile.camera_range,
        head_pan_range=profile.pan_range, head_tilt_range=profile.tilt_range,
        gestures=dict(profile.gestures),
    )


class Loaded:
    """Maps, robot profiles and documents loaded for runs, kept by file and content, so
    that runs of the same files (a sweep's) read and check each file once. Maps,
    profiles and documents are immutable: runs share them. A file that cannot be
    loaded is not kept (each run reports it as it would alone).

    ``unchanging``: the caller promises that no file the runs read changes, moves or is
    replaced while they run, and that the working folder stays (a sweep's worker, its
    bundle unpacked in a folder of its own). Each file is then kept by its path alone,
    not read again to see whether it changed, and where the paths a scenario writes lead
    (:meth:`resolve`) and how a run names a file (:meth:`relative`) are worked out once:
    a run of a sweep reads only its own scenario."""

    def __init__(self, unchanging: bool = False) -> None:
        self.unchanging = unchanging
        self._maps: dict[tuple[str, bytes], WorldMap] = {}
        self._profiles: dict[tuple[str, bytes], RobotProfile] = {}
        self._documents: dict[tuple[str, bytes], tuple[RobotProfile, Document]] = {}
        self._places: dict[tuple[str, str], Path] = {}
        self._names: dict[tuple[str, str], str] = {}

    def map(self, path: Path) -> WorldMap:
        """The map in ``path`` (:func:`prima.scenario.load_map`)."""
        return _kept(self._maps, self._key(path), path, load_map)

    def profile(self, path: str | Path) -> RobotProfile:
        """The robot profile in ``path`` (:func:`prima.dsl.load_profile`)."""
        return _kept(self._profiles, self._key(path), path, load_profile)

    def document(self, path: str | Path, profile: RobotProfile) -> Document:
        """The document in ``path``, checked for ``profile``
        (:func:`prima.dsl.load_document`)."""
        key = self._key(path)
        if key is None:
            return load_document(path, profile)
        found = self._documents.get(key)
        if found is not None and found[0] is profile:
            return found[1]
        document = load_document(path, profile)
        self._documents[key] = (profile, document)
        return document

    def resolve(self, scenario: Scenario, path: str) -> Path:
        """Where ``path``, written in ``scenario``, leads (:meth:`Scenario.resolve`): kept
        by the scenario's folder when :attr:`unchanging` (a sweep's runs are variants
        of one scenario, in one folder)."""
        if not self.unchanging:
            return scenario.resolve(path)
        key = (os.path.dirname(scenario.source), path)
        found = self._places.get(key)
        if found is None:
            found = self._places[key] = scenario.resolve(path)
        return found

    def relative(self, path: str, folder: str) -> str:
        """``path`` relative to the absolute ``folder``, as a run's error lines name a
        file it read: kept when :attr:`unchanging`."""
        if not self.unchanging:
            return os.path.relpath(os.path.abspath(path), folder)
        key = (path, folder)
        found = self._names.get(key)
        if found is None:
            found = self._names[key] = os.path.relpath(os.path.abspath(path), folder)
        return found

    def _key(self, path: str | Path) -> tuple[str, bytes] | None:
        """What a file is kept by: its path, and its content unless :attr:`unchanging`;
        None for a file that cannot be read."""
        if self.unchanging:
            return str(path), b""
        try:
            return str(path), Path(path).read_bytes()
        except OSError:
            return None


_Loadable = TypeVar("_Loadable")


def _kept(kept: dict[tuple[str, bytes], _Loadable], key: tuple[str, bytes] | None,
          path: str | Path, load: Callable[[str | Path], _Loadable]) -> _Loadable:
    """What ``load`` makes of the file ``path``, kept by ``key`` (:meth:`Loaded._key`;
    None: not kept)."""
    if key is None:
        return load(path)  # (which says what is wrong with the file)
    found = kept.get(key)
    if found is None:
        found = kept[key] = load(path)
    return found


@dataclass(frozen=True)
class Switches:
    """What a command line may change of a scenario's own choices for its runs (``prima
    run``, ``judge``, ``sweep``, ``test``, ``show``, ``plot`` alike): its FA, its EA,
    its robot profile, and mediation policy switches (over the profile's and the
    scenario's, a later one winning)."""

    fa: str | None = None
    ea: str | None = None
    robot: str | None = None
    policies: tuple[tuple[str, bool], ...] = ()

    def __bool__(self) -> bool:
        return bool(self.fa or self.ea or self.robot or self.policies)

    def run_options(self) -> dict[str, Any]:
        """The keyword arguments of :class:`Run` they stand for."""
        return {"fa": self.fa, "ea": self.ea, "robot": self.robot,
                "policies": dict(self.policies)}


@dataclass(frozen=True)
class Setup:
    """A scenario made ready to run (see the module): what :class:`~prima.run.Run` needs
    before it builds the simulator, the mediator and the interpreters. Loading it checks
    everything that can be checked before a run starts: a broken file stops here."""

    scenario: Scenario
    """The scenario, its seed the caller's if given."""
    until: float
    """When the run ends (s): the caller's, else the scenario's (not yet on the
    simulator's grid)."""
    profile: RobotProfile
    catalog: Catalog
    """The Commands the robot offers (the profile's)."""
    spec: RobotSpec
    """The simulator's physical figures (the profile's)."""
    policies: Mapping[str, bool]
    """Every mediation policy's state: the defaults, switched by the profile, the
    scenario and the caller, in that order (docs/rules.md 7.3)."""
    config: MediatorConfig
    """The mediator's configuration: the profile's budgets and hearing, the policies."""
    fa_path: Path | None
    ea_path: Path | None
    ea_paths: tuple[Path, ...]
    """The EAs running from the start (``<apps ea>`` or ``ea=``, then ``<apps><ea>``)."""
    documents: Mapping[Path, Document]
    """The documents running from the start, each checked in its slot."""
    read: tuple[str, ...]
    """Every file read, in the order read (a run names them relative to the scenario's
    folder in its error lines)."""
    files: Loaded
    """Where maps, profiles and documents were loaded (a sweep's runs share it)."""

    @classmethod
    def load(cls, scenario: str | Path, *, fa: str | Path | None = None,
             ea: str | Path | None = None, robot: str | Path | None = None,
             seed: int | None = None, until: float | None = None,
             policies: Mapping[str, bool] | None = None,
             files: Loaded | None = None) -> Setup:
        """The scenario in ``scenario`` made ready, with what the caller changes of it
        (its FA, EA, robot profile, seed, end, policy switches). Raises ScenarioError or
        DocumentError, located, for a file that cannot run."""
        files = files or Loaded()
        loaded = load_scenario(scenario, files.map)
        if seed is not None:
            loaded = dataclasses.replace(loaded, seed=seed)
        read = [loaded.source]
        place = files.resolve
        profile_path = robot or (place(loaded, loaded.profile) if loaded.profile else None)
        profile = files.profile(profile_path) if profile_path else default_profile()
        switched = policy_settings(profile.policies, loaded.policies, policies or {})
        fa_path = Path(fa) if fa else (place(loaded, loaded.fa) if loaded.fa else None)
        ea_path = Path(ea) if ea else (place(loaded, loaded.ea) if loaded.ea else None)
        ea_paths = ([ea_path] if ea_path else []) + [place(loaded, more) for more in loaded.eas]
        documents = _starting(loaded, profile, files, fa_path, ea_paths, read)
        return cls(loaded, loaded.until if until is None else until, profile,
                   profile.catalog(), spec_from_profile(profile), switched,
                   mediator_config(profile, switched), fa_path, ea_path, tuple(ea_paths),
                   documents, tuple(read), files)

    def document(self, path: Path, role: AppKind, read: list[str] | None = None) -> Document:
        """The document in ``path`` checked for ``role`` (:func:`checked`)."""
        return checked(self.scenario, self.profile, self.files, path, role, read)


def mediator_config(profile: RobotProfile, policies: Mapping[str, bool]) -> MediatorConfig:
    """The mediator's configuration for a robot profile and the policies' states: each
    policy switches the field its entry names (:attr:`prima.vocab.Policy.config`)."""
    switched: dict[str, Any] = {p.config: policies[p.name] for p in POLICIES.values()
                                if p.config is not None}
    return MediatorConfig(budgets=profile.budgets, resume_pause=profile.hearing.pause,
                          **switched)


def checked(scenario: Scenario, profile: RobotProfile, files: Loaded, path: Path,
            role: AppKind, read: list[str] | None = None) -> Document:
    """A document loaded for ``role``, its places written by name on the scenario's map
    (as ``prima validate`` of the scenario checks them): else the problems. Each file
    read is noted in ``read``."""
    notes = read if read is not None else []
    notes.append(str(path))
    document = check_slot(files.document(path, profile), role)
    notes.append(str(document.path))
    world = scenario.map
    problems = unknown_places(str(path), document.places, [p.name for p in world.places],
                              world.name, world.source)
    if problems:
        raise DocumentError(problems)
    return document


def _starting(scenario: Scenario, profile: RobotProfile, files: Loaded, fa_path: Path | None,
              ea_paths: list[Path], read: list[str]) -> dict[Path, Document]:
    """The documents running from the start, loaded up front: a broken one stops the run
    before it starts; two applications of one name too."""
    documents: dict[Path, Document] = {}
    named: dict[str, tuple[Path, AppKind]] = {}
    starting = [(fa_path, AppKind.FA)] + [(p, AppKind.EA) for p in ea_paths]
    for path, role in starting:
        if path is None:
            continue
        document = checked(scenario, profile, files, path, role, read)
        documents[path] = document
        other = named.get(document.name)
        if other is not None:
            whom = ("the FA and the EA" if other[1] is AppKind.FA
                    else f"the EAs '{other[0]}' and '{path}'")
            raise DocumentError([Problem(str(path), 1, 1, Severity.ERROR,
                                         f"{whom} are both named '{document.name}'; "
                                         "each application needs a name of its own")])
        named[document.name] = (path, role)
    return documents
