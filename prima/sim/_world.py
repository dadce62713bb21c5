"""The physical world: a pymunk space with walls, the robot and the user.

The robot is a dynamic round body (walls and the user block it) whose wheels
are driven by one of three controllers, all stepped at the fixed time step:

* a *linear profile* (drive straight to a point: accelerate, cruise, brake),
* an *angular profile* (turn in place by an angle),
* a *velocity command* (wanted speed and turning rate, reached within the
  acceleration limits; used by Tracking Human and Set Speed and Time).

Per-step Python work is kept small: pymunk property access costs more than a
physics step here, so velocities are written only when they change and the
profiles keep their own progress instead of reading positions back. What the
world does at every step, and the poses it reads most, go straight to the
Chipmunk functions that pymunk's properties and ``Space.step`` call (through
pymunk's own binding of them): the same calls with the same numbers, without
three to five times their cost in Python around each. The simulator steps the world a
stretch of steps at a time (:meth:`World.run`: the steps between two sensing ticks),
in a loop of the wheels' controller's own (:meth:`World.step`: a stretch of one).

What is worked out from the poses is worked out once per pose: :attr:`World.version`
moves on whenever a body may have moved or turned (every step, and every pose
written through the world's methods), and human detection keeps its answer
until the version or the camera's pan changes; then it looks again
only if something moved: the robot, the user or the camera (a step in which
nothing moved keeps the answer). The poses themselves are read once per version
too (the robot's and the user's position, the robot's angle: a run reads each
several times over at one version, from the senses, the behaviors, the scripted
user and the trace, and a read through Chipmunk costs more than a kept one). So
the version moves on after every pose written, before anything can read it: a
stretch of steps moves it on after its last step and whatever its end writes (a
drive's snap to its goal, a turn's final angle); a pose written on a body directly,
from outside, must be followed by :meth:`World.moved`. Within a stretch (the
version not yet moved on) the world reads its bodies afresh.

A robot is checked for a push (the user walking into it, a wall it drives into)
after the first step of each stretch and after each step in which it touched
something: Chipmunk says so (a handler of the robot's contacts, called only for a
step with one, sets :attr:`World._touched`). A step changes the robot's speed only
through a contact (the space has no gravity and no damping), so every other step
leaves it the speed the check before it left: reading it again would find the same.

Where nothing can touch the robot, the world works its steps out without Chipmunk:
idle or turning in place (:meth:`World._glides`), driving straight
(:meth:`World._glides_straight`) or by a velocity command (:meth:`World._glides_free`),
it has touched nothing for Chipmunk's collision persistence (so Chipmunk keeps no
contact of its, and its velocity is the one its controller set), nothing sways it, and
neither a wall nor the user can come within reach in the stretch. A step then only
moves the bodies at their velocities, which the world works out as Chipmunk's position
update does, to the last bit (``p + (v + 0) * dt``, ``a + (w + 0) * dt``: the tests
compare them). The poses are then kept in Python and written to Chipmunk only before
its next step or when the bodies are handed out (:meth:`World._sync`); nearly all the
steps of a run are worked out so (:attr:`World.glided`). What such steps do not do is
Chipmunk's broad phase (its tree of the bodies' bounding boxes, which it updates at a
step only for a body that left the box it last had): so where the robot later touches
two walls at once, Chipmunk may meet the two contacts in the other order, and solve
them to other last bits than it would have (a corner scraped: in 2 of 1,360 jittered
runs of the shipped scenarios, the user's touch 0.2 s off).

The map files its places and walls by the squares of a grid (made once per map, not
per run): :meth:`World.places_near` asks it which places may be near a point
(:meth:`WorldMap.places_along`), instead of measuring the distance to every place, and
says how far the point may move before the answer can change; :meth:`World.clear`
asks it which walls may be near a segment fattened by a radius
(:meth:`WorldMap.walls_along`), instead of asking every wall.

The user is a kinematic body moved by the scripted user. Head and arm
angles, and those of the joints a robot profile declares (a laser pointer's
pan), are interpolated on demand, never stepped.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Final

import pymunk
from pymunk._chipmunk_cffi import ffi as _ffi  # (pymunk's binding of Chipmunk: see above)
from pymunk._chipmunk_cffi import lib as _cp

from prima.sim._maps import WorldMap
from prima.sim._records import Pose
from prima.sim._spec import RobotSpec

__all__ = ["World", "wrap_angle"]

# What the hot paths call, each as a constant: compiled, a Final name is a C static,
# where ``_cp.cpSpaceStep`` is a lookup in the module's dict and one in the binding's,
# and ``math.hypot`` one in the module's and one in ``math``'s (some 300 to 500
# instructions), at every call: a run makes tens of thousands.
_cpBodyGetAngle: Final = _cp.cpBodyGetAngle
_cpBodyGetAngularVelocity: Final = _cp.cpBodyGetAngularVelocity
_cpBodyGetPosition: Final = _cp.cpBodyGetPosition
_cpBodyGetVelocity: Final = _cp.cpBodyGetVelocity
_cpBodySetAngle: Final = _cp.cpBodySetAngle
_cpBodySetAngularVelocity: Final = _cp.cpBodySetAngularVelocity
_cpBodySetPosition: Final = _cp.cpBodySetPosition
_cpBodySetVelocity: Final = _cp.cpBodySetVelocity
_cpSpacePointQueryNearest: Final = _cp.cpSpacePointQueryNearest
_cpSpaceSegmentQueryFirst: Final = _cp.cpSpaceSegmentQueryFirst
_cpShapeSegmentQuery: Final = _cp.cpShapeSegmentQuery
_cpSpaceStep: Final = _cp.cpSpaceStep
_hypot: Final = math.hypot
_atan2: Final = math.atan2
_degrees: Final = math.degrees
_radians: Final = math.radians
_INF: Final = math.inf
_NULL: Final = _ffi.NULL

WALL = 0b001
ROBOT = 0b010
HUMAN = 0b100
_SIGHTED: Final = _ffi.new("cpShapeFilter *", tuple(pymunk.ShapeFilter(mask=WALL)))
_SIGHT: Final = _SIGHTED[0]
"""What hides the user from the camera: the walls (a filter as Chipmunk takes it, made
once: a ``ShapeFilter`` is converted field by field at every query)."""
_NEAREST: Final = _ffi.new("cpPointQueryInfo *")
"""Where Chipmunk says which wall is nearest (:meth:`World._walls_far`), made once."""
HUMAN_RADIUS = 0.25
_PLACE_MARGIN: Final = 1e-3
"""A margin (m) for rounding: the places' index is asked about a box this much
wider than needed, and the distance a point may move without changing which
places are near it is this much shorter than measured."""

_IDLE: Final = 0
_LINEAR: Final = 1
_ANGULAR: Final = 2
_VELOCITY: Final = 3

_CHECK_EVERY: Final = 5
"""A straight drive compares its real progress with its plan every this many steps
(reading the body's position costs more than a physics step)."""
_MARGIN: Final = 1e-9
"""A length (m) far longer than the rounding of a straight drive's progress over a
stretch of steps, far shorter than a step."""
_GLIDE_MARGIN: Final = 0.01
"""How far (m) the user and the walls must stay from touching the robot for the steps
between them to be worked out without Chipmunk (:meth:`World._glides`): far wider than
the rounding of the distance, which is all a contact waits for (Chipmunk's circles
touch when they overlap)."""
_ROOM: Final = 1.0
"""How much farther (m) than a stretch needs :meth:`World._walls_far` looks for walls: the
room found there serves the stretches after."""
_ROBOT_KIND: Final = 1
"""The robot's shape's collision type: :func:`_touching` is told of its contacts."""
_BLOCKED_LAG: Final = 0.1
"""A straight drive that lags this far (m) behind its plan is blocked: it ends at once."""
STILL: Final = 1e-4
"""The wheels' least speed (m/s) and turning rate (rad/s): a controller that asks for
less asks them to stand still (at this bound the robot would creep a millimetre, or 0.06
degrees, in ten seconds). A proportional controller that has nearly converged (a robot
following a user who stands) asks for less and less, down to what is left of its
arithmetic (1e-14): the robot did not move, yet the world was stepped 50 times a second,
a third of a run's physics steps."""

Done = Callable[[bool], None]
"""Called when a profile motion ends; the flag is True if it arrived, False if blocked."""


_UNSEEN: tuple[int, float, tuple[float, ...], tuple[bool, float]] = (
    -1, math.nan, (), (False, _INF))
"""Human detection's answer before it first looks (:attr:`World._ahead`): at no version,
for no pan (NaN equals nothing)."""


def _length(v: Any) -> float:
    """A velocity's length, as ``Vec2d.length`` works it out (pymunk's ``body.velocity``)."""
    return math.sqrt(v.x**2 + v.y**2)


def _touching(_arbiter: object, _space: object, touched: list[bool]) -> None:
    """The robot touches something in this step (Chipmunk calls it before it works out
    the contact's push): :attr:`World._touched` says so until a check reads it. (It is
    handed that list, not the world: the space does not hold the world.)"""
    touched[0] = True


def _toward(value: float, target: float, step: float) -> float:
    """``value`` moved toward ``target`` by at most ``step``: a velocity command's speed
    or turning rate after one step (the same arithmetic for a step Chipmunk takes and one
    worked out without it)."""
    d = target - value
    return value + (d if -step <= d <= step else (step if d > 0 else -step))


def wrap_angle(a: float) -> float:
    """An angle in radians brought into [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


class _Joint:
    """A head or arm angle moving linearly between two ticks (computed on demand)."""

    __slots__ = ("a0", "a1", "t0", "t1")

    def __init__(self, value: float = 0.0) -> None:
        self.a0 = self.a1 = value
        self.t0 = self.t1 = 0

    def at(self, tick: int) -> float:
        if tick >= self.t1:
            return self.a1
        if tick <= self.t0:
            return self.a0
        return self.a0 + (self.a1 - self.a0) * (tick - self.t0) / (self.t1 - self.t0)

    def move(self, target: float, tick: int, ticks: int) -> None:
        self.a0 = self.at(tick)
        self.a1 = target
        self.t0 = tick
        self.t1 = tick + ticks


def _add_walls(space: pymunk.Space,
               world_map: WorldMap) -> list[tuple[float, float, float, float, Any]]:
    """The map's walls, as static segments of the space (which nothing moves); returns
    each one's bounding box (left, bottom, right, top) and its shape as Chipmunk knows
    it."""
    out = []
    for w in world_map.walls:
        seg = pymunk.Segment(space.static_body, (w.x1, w.y1), (w.x2, w.y2), w.thickness / 2)
        seg.filter = pymunk.ShapeFilter(categories=WALL)
        seg.friction = 0.0
        space.add(seg)
        bb = seg.cache_bb()
        out.append((bb.left, bb.bottom, bb.right, bb.top, seg._shape))
    return out


class World:
    """The pymunk space and the bodies in it, stepped at ``1 / hz`` seconds."""

    def __init__(self, world_map: WorldMap, spec: RobotSpec, hz: int,
                 robot: Pose, user: Pose | None) -> None:
        self.map = world_map
        self.spec = spec
        self.hz = hz
        self.dt = 1.0 / hz
        space = pymunk.Space()
        space.collision_slop = 0.005  # metres: the default 0.1 would let bodies sink 10 cm
        self._walls = _add_walls(space, world_map)  # (their boxes and shapes: _clear)
        body = pymunk.Body(20.0, float("inf"))
        body.position = (robot.x, robot.y)
        body.angle = _radians(robot.heading)
        shape = pymunk.Circle(body, spec.radius)
        shape.filter = pymunk.ShapeFilter(categories=ROBOT)
        shape.friction = 0.0
        shape.collision_type = _ROBOT_KIND
        space.add(body, shape)
        self._robot = body
        self._touched = [False]
        """Whether the robot touched something since its speed was last checked."""
        space.on_collision(_ROBOT_KIND, None, pre_solve=_touching, data=self._touched)
        self._space = space
        self.has_user = user is not None
        human = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        start = user or Pose(-1000.0, -1000.0)
        human.position = (start.x, start.y)
        human.angle = self._ha = _radians(start.heading)
        hshape = pymunk.Circle(human, HUMAN_RADIUS)
        hshape.filter = pymunk.ShapeFilter(categories=HUMAN)
        space.add(human, hshape)
        self._human = human
        self._rb, self._hb, self._sp = body._body, human._body, space._space
        """The robot, the user and the space as Chipmunk knows them."""
        self._start_glides(space, spec)
        self.version = 0
        """Moves on whenever a body may have moved or turned (see the module's doc)."""
        self._pk = self._ak = -1  # (the kept reads, of no version yet: :meth:`_read`)
        self._rxy, self._hxy, self._ra = (0.0, 0.0), (0.0, 0.0), 0.0
        self._ahead: tuple[int, float, tuple[float, ...], tuple[bool, float]] = _UNSEEN
        self._around = _UNSEEN
        """Human detection's last answer without and with ``any_direction``: the
        version, the camera's pan and the poses it was worked out for, and the answer
        (one attribute each: asked again at the same version, as it mostly is, it is
        found at once)."""
        self.head_pan = _Joint()
        self.head_tilt = _Joint()
        self.arm = _Joint()
        self.joints: dict[str, _Joint] = {}
        """Joints a robot profile declares (a laser pointer's pan), by name: each
        at 0 until a Command's ``<perform>`` first moves it."""
        self.joints_until = 0
        # robot wheel controller
        self.mode = _IDLE
        self._done: Done | None = None
        self._on_stopped: list[Callable[[], None]] = []
        self._v = 0.0  # current speed along the motion (m/s or rad/s)
        self._s = 0.0  # progress along the profile
        self._len = 0.0
        self._ux = self._uy = 0.0
        self._tx = self._ty = self._ta = self._x0 = self._y0 = 0.0
        self._steps = 0
        self._cmd_v = self._cmd_w = 0.0
        self._w = 0.0
        self._a_dt = spec.max_accel * self.dt
        self._alpha_dt = _radians(spec.turn_accel) * self.dt
        # how fast it drives now: the lower of the limit (speed_limit) and the running
        # straight drive's own speed (drive_to: its cap), and turns (turn_by: the turn's)
        self._vmax = self._limit = spec.max_speed
        self._cap = _INF
        self._wmax = self._wtop = _radians(spec.max_turn_rate)
        # a sway superimposed on whatever drives the wheels (a dance step: the blend policy)
        self._sway: tuple[float, float, int] | None = None
        """Amplitude (rad), angular frequency (rad per step) and length (steps)."""
        self._sway_k = 0
        self._sway_offset = 0.0
        """How far (rad) the sway has turned the body from where it would be."""
        self._ta_offset = 0.0
        """The sway's offset when the running turn began."""
        self.sway_owner = 0
        """The Command whose sway runs (0: none)."""

    def _start_glides(self, space: pymunk.Space, spec: RobotSpec) -> None:
        """What :meth:`_glides` keeps: the user's velocity, the calm, the user's
        position while Chipmunk's is behind."""
        self.human_moving = False
        self._hv = (0.0, 0.0)
        """The user's velocity (m/s), as :meth:`walk_user` last wrote it."""
        self._calm = 0
        """Physics steps in a row in which the robot touched nothing (at least: a velocity
        command's stretch that touched something counts none of its steps): after
        ``_persist`` of them Chipmunk keeps no contact of the robot's (see :meth:`_glides`);
        a drive's end (put at its goal) starts it again."""
        self._persist = int(space.collision_persistence)
        self._still: bool | None = None
        """Whether the robot's velocity is exactly nought, as read since the calm began
        (None: not read; idle, nothing turns it)."""
        self._lazy = False
        """True while steps worked out without Chipmunk (:meth:`_glide_user`) have left the
        user's position in Chipmunk behind: ``_lx``, ``_ly`` are it (:meth:`_sync`)."""
        self._lx = self._ly = 0.0
        self._rlazy = False
        """The same for the robot's position (:meth:`_glide_linear`,
        :meth:`_glide_velocity`): ``_rx``, ``_ry``."""
        self._rx = self._ry = 0.0
        self._rvlazy = False
        """The same for the robot's heading, velocity and turning rate (steps of a velocity
        command: :meth:`_glide_velocity`): ``_rang``, ``_rvx``, ``_rvy``, ``_rw``."""
        self._rang = self._rvx = self._rvy = self._rw = 0.0
        self._room = -1.0
        """How far (m) the robot may move from where it is before a wall could come within
        reach (:meth:`_walls_far`); negative: not known."""
        self._open = False
        """The running straight drive's path, from where the robot is on it to its end, is
        clear of walls by the robot's radius and :data:`_GLIDE_MARGIN` (asked once a calm
        of a drive: untouched, the robot keeps to that line)."""
        self.glided = 0
        """Physics steps worked out without Chipmunk so far (:meth:`_glides`): of the
        steps the world took, those Chipmunk did not."""
        self._reach = spec.radius + HUMAN_RADIUS + _GLIDE_MARGIN

    # ---- the bodies ------------------------------------------------------------

    @property
    def space(self) -> pymunk.Space:
        """The pymunk space, its bodies where the world says they are (:meth:`_sync`)."""
        self._sync()
        return self._space

    @property
    def robot(self) -> pymunk.Body:
        """The robot's pymunk body, where the world says the robot is (:meth:`_sync`)."""
        self._sync()
        return self._robot

    @property
    def human(self) -> pymunk.Body:
        """The user's pymunk body, where the world says the user is (:meth:`_sync`)."""
        self._sync()
        return self._human

    def _sync(self) -> None:
        """Write the user's and the robot's poses to Chipmunk if steps worked out without
        it (:meth:`_glide_user`, :meth:`_glide_linear`, :meth:`_glide_velocity`) left them
        behind: before any real step, and before the bodies are handed out."""
        if self._lazy:
            self._lazy = False
            _cpBodySetPosition(self._hb, (self._lx, self._ly))
        if self._rvlazy:
            self._rvlazy = False
            rb = self._rb
            _cpBodySetAngle(rb, self._rang)
            _cpBodySetVelocity(rb, (self._rvx, self._rvy))
            _cpBodySetAngularVelocity(rb, self._rw)
        if self._rlazy:
            self._rlazy = False
            _cpBodySetPosition(self._rb, (self._rx, self._ry))

    # ---- queries -------------------------------------------------------------

    def joint(self, name: str) -> _Joint:
        """A joint by name: ``head-pan``, ``head-tilt``, ``arm``, or one a profile
        declares (the profile bounds how many there are)."""
        builtin = {"head-pan": self.head_pan, "head-tilt": self.head_tilt, "arm": self.arm}
        found = builtin.get(name)
        if found is None:
            found = self.joints.setdefault(name, _Joint())
        return found

    def joint_angle(self, name: str, tick: int) -> float:
        """A joint's angle now (deg); 0 for one never moved."""
        return self.joint(name).at(tick)

    def robot_pose(self) -> Pose:
        x, y = self.robot_xy()
        return Pose(x, y, _degrees(self.robot_angle()) % 360.0)

    def user_pose(self) -> Pose:
        x, y = self.user_xy()
        return Pose(x, y, _degrees(self._ha) % 360.0)

    def _read(self) -> None:
        """Read the robot's and the user's positions afresh, at a new version: kept in
        ``_rxy`` and ``_hxy`` while ``_pk`` is the version (read together: most versions
        that read one read both). The robot's angle is kept as ``_ra`` while ``_ak`` is
        (:meth:`robot_angle`)."""
        if self._rlazy:
            self._rxy = (self._rx, self._ry)
        else:
            r = _cpBodyGetPosition(self._rb)
            self._rxy = (r.x, r.y)
        if self._lazy:
            self._hxy = (self._lx, self._ly)
        else:
            h = _cpBodyGetPosition(self._hb)
            self._hxy = (h.x, h.y)
        self._pk = self.version

    def robot_xy(self) -> tuple[float, float]:
        """Where the robot is (m): ``robot.position``, read for less (once a version)."""
        if self._pk != self.version:
            self._read()
        return self._rxy

    def user_xy(self) -> tuple[float, float]:
        """Where the user is (m): ``human.position``, read for less (once a version)."""
        if self._pk != self.version:
            self._read()
        return self._hxy

    def robot_angle(self) -> float:
        """The robot's body angle (radians): ``robot.angle``, read for less (once a
        version)."""
        if self._ak != self.version:
            self._ra = self._rang if self._rvlazy else float(_cpBodyGetAngle(self._rb))
            self._ak = self.version
        return self._ra

    def turning_rate(self) -> float:
        """How fast the robot's body turns (rad/s): ``robot.angular_velocity``, without
        handing the body out (:attr:`robot`)."""
        return self._rw if self._rvlazy else float(_cpBodyGetAngularVelocity(self._rb))

    def user_angle(self) -> float:
        """The user's body angle (radians): ``human.angle``, as last written (the world
        writes it, and nothing turns the user: a step adds their turning rate, nought,
        which can only make a -0.0 0.0)."""
        return self._ha

    def user_distance(self) -> float:
        if self._pk != self.version:
            self._read()
        rx, ry = self._rxy
        ux, uy = self._hxy
        return _hypot(ux - rx, uy - ry)

    def clear(self, ax: float, ay: float, bx: float, by: float, radius: float = 0.0) -> bool:
        """True if no wall lies on the segment from a to b (fattened by ``radius``)."""
        return self._clear((ax, ay), (bx, by), radius)

    def _clear(self, a: tuple[float, float], b: tuple[float, float], radius: float) -> bool:
        if radius <= 0.0:
            # (Space.segment_query_first, without the result's Python objects)
            return bool(_cpSpaceSegmentQueryFirst(self._sp, a, b, 0.0, _SIGHT, _NULL)
                        == _NULL)
        # Chipmunk's query of the space fattens the segment only where it asks a shape:
        # it asks the shapes whose bounding boxes the thin segment crosses, so a wall
        # within ``radius`` of it beside it (along a drive, by a doorway) is never asked.
        # Each wall the map files near the segment, whose box lies within ``radius`` of
        # the segment's, is asked itself.
        (ax, ay), (bx, by) = a, b
        x0, x1 = (ax - radius, bx + radius) if ax < bx else (bx - radius, ax + radius)
        y0, y1 = (ay - radius, by + radius) if ay < by else (by - radius, ay + radius)
        walls = self._walls
        for i in self.map.walls_along(ax, ay, bx, by, radius):
            left, bottom, right, top, shape = walls[i]
            if (left <= x1 and right >= x0 and bottom <= y1 and top >= y0
                    and _cpShapeSegmentQuery(shape, a, b, radius, _NULL)):
                return False
        return True

    def camera_heading(self, tick: int) -> float:
        """Where the head camera looks (radians, map frame)."""
        return self.robot_angle() + _radians(self.head_pan.at(tick))

    def sees_user(self, tick: int, *, any_direction: bool = False) -> tuple[bool, float]:
        """Human detection: in range, in the camera's field of view, in line of sight.

        With ``any_direction`` the field of view is ignored (the robot senses
        the user around it, as Face Human needs). Returns (seen, distance).
        """
        if any_direction:
            pan = 0.0
            kept = self._around
        else:
            head = self.head_pan
            pan = head.a1 if tick >= head.t1 else head.at(tick)  # (at rest: at()'s first case)
            kept = self._ahead
        if kept[0] == self.version and kept[1] == pan:
            return kept[3]  # (the same poses, the camera the same way: at any tick)
        if not self.has_user:
            return False, _INF
        if self._pk != self.version:
            self._read()
        rx, ry = self._rxy
        ux, uy = self._hxy
        angle = 0.0 if any_direction else self.robot_angle()
        poses = (rx, ry, angle, ux, uy)
        if kept[1] == pan and kept[2] == poses:
            seen = kept[3]  # nothing moved since it last looked
        else:
            seen = self._look(pan, angle, any_direction, rx, ry, ux, uy)
        if any_direction:
            self._around = (self.version, pan, poses, seen)
        else:
            self._ahead = (self.version, pan, poses, seen)
        return seen

    def _look(self, pan: float, angle: float, any_direction: bool, rx: float, ry: float,
              ux: float, uy: float) -> tuple[bool, float]:
        dx = ux - rx
        dy = uy - ry
        d = _hypot(dx, dy)
        if d > self.spec.camera_range:
            return False, d
        if not any_direction:
            rel = wrap_angle(_atan2(dy, dx) - (angle + _radians(pan)))
            if abs(rel) > _radians(self.spec.camera_fov) / 2:
                return False, d
        # (:meth:`_clear`, written out: a look at each sensing tick while anything moves)
        hit = _cpSpaceSegmentQueryFirst(self._sp, (rx, ry), (ux, uy), 0.0, _SIGHT, _NULL)
        return bool(hit == _NULL), d

    def places_near(self, x: float, y: float, radius: float,
                    slack: float = 0.0) -> tuple[list[int], float]:
        """The places within ``radius`` of (x, y), as indices in the map's order, and
        how far (m) the point may move before any place comes within ``radius`` or
        leaves it (at most ``slack``).

        The map's index of its places finds the candidates within ``radius +
        slack`` (:meth:`WorldMap.places_along`); each is then measured as a scan of
        every place would measure it, so the places found are the scan's.
        """
        m = radius + slack + _PLACE_MARGIN
        places = self.map.places
        found = []
        clear = slack
        for i in sorted(self.map.places_along(x, y, x, y, m)):
            d = _hypot(places[i].x - x, places[i].y - y)
            if d <= radius:
                found.append(i)
            clear = min(clear, abs(d - radius))
        return found, clear - _PLACE_MARGIN

    def user_bearing(self) -> float:
        """Direction from the robot to the user relative to the body (radians)."""
        if self._pk != self.version:
            self._read()
        rx, ry = self._rxy
        ux, uy = self._hxy
        return wrap_angle(_atan2(uy - ry, ux - rx) - self.robot_angle())

    # ---- poses written from outside the step --------------------------------------

    def moved(self) -> None:
        """A body's pose was written directly: forget what was worked out from the poses
        (and the calm: a body put against another touches it at the next step)."""
        self.version += 1
        self._calm = 0
        self._still = None
        self._open = False
        self._room = -1.0

    def put_user(self, x: float, y: float) -> None:
        """Put the user at (x, y) now."""
        self.human.position = (x, y)
        self.moved()

    def walk_user(self, vx: float, vy: float) -> None:
        """Move the user at (vx, vy) m/s from the next step on, facing the way they walk."""
        _cpBodySetVelocity(self._hb, (vx, vy))  # (what ``human.velocity = ...`` calls)
        self._hv = (vx, vy)
        self.human_moving = vx != 0.0 or vy != 0.0
        if self.human_moving:
            self._ha = _atan2(vy, vx)
            _cpBodySetAngle(self._hb, self._ha)
            self.version += 1

    # ---- robot wheel commands --------------------------------------------------

    def heading_to(self) -> tuple[float, float] | None:
        """Where the running straight drive goes, if one runs."""
        return (self._tx, self._ty) if self.mode == _LINEAR else None

    def speed_limit(self, speed: float) -> None:
        """Drive no faster than ``speed`` (m/s) from now on (a blend slows the robot)."""
        self._limit = min(speed, self.spec.max_speed)
        self._capped(self._cap)

    def _capped(self, speed: float) -> None:
        """The running straight drive's own speed is ``speed`` (m/s; infinite: none)."""
        self._cap = speed
        self._vmax = min(self._limit, speed)

    def speed_cap(self) -> float:
        """The fastest the robot drives now (m/s)."""
        return self._vmax

    def sway(self, amplitude: float, sways: int, steps: int, owner: int) -> None:
        """Sway the body about its heading, ``amplitude`` radians either way, ``sways``
        whole times in ``steps`` steps, on top of whatever drives the wheels (alone it
        turns to and fro in place; over a drive, the course is unchanged and the body
        swings about it). It ends facing where it would have faced without it."""
        self.end_sway()
        if steps > 0 and sways > 0:
            self._sway = (amplitude, 2.0 * math.pi * sways / steps, steps)
            self._sway_k = 0
            self._sway_offset = 0.0
            self.sway_owner = owner

    def end_sway(self) -> None:
        """Stop a sway under way (its atomic behavior ended early): the body turns back
        by what it had swayed."""
        if self._sway is None:
            return
        body = self.robot
        body.angle -= self._sway_offset
        body.angular_velocity = self._base_w()
        self._sway = None
        self._sway_offset = 0.0
        self.sway_owner = 0
        self.version += 1

    def _base_w(self) -> float:
        """The turning rate the wheels' controller gives the body (rad/s)."""
        if self.mode == _ANGULAR:
            return self._ux * self._v
        if self.mode == _VELOCITY:
            return self._w
        return 0.0

    def _advance(self, space: object, dt: float) -> None:
        """Step the physics with the sway under way on top of the wheels: in a stretch
        with a sway, the step the loops of :meth:`run` take instead of
        ``cpSpaceStep(space, dt)`` (the same arguments; the wheels' turning rate, which
        the sway adds to, is the controller's attribute: the loops keep it up to date)."""
        sway = self._sway
        if sway is None:  # (it ended within the stretch)
            _cpSpaceStep(space, dt)
            return
        amplitude, omega, steps = sway
        k = self._sway_k + 1
        offset = amplitude * math.sin(omega * k) if k < steps else 0.0
        rb = self._rb
        base = self._base_w()
        _cpBodySetAngularVelocity(rb, base + (offset - self._sway_offset) / dt)
        _cpSpaceStep(space, dt)
        self._sway_offset = offset
        self._sway_k = k
        if k >= steps:
            self._sway = None
            self.sway_owner = 0
            _cpBodySetAngularVelocity(rb, base)

    def turning_to(self) -> float | None:
        """The body angle the running turn ends at (radians), if one runs."""
        return self._ta if self.mode == _ANGULAR else None

    def when_done(self, done: Done) -> None:
        """Call ``done`` instead when the running drive or turn ends (it goes on as is)."""
        self._done = done

    def drive_to(self, x: float, y: float, done: Done, speed: float = _INF) -> bool:
        """Drive straight to (x, y) from standstill, no faster than ``speed`` (m/s), if
        that is below the limit. False if already there."""
        px, py = self.robot_xy()
        length = _hypot(x - px, y - py)
        self._halt()
        self._capped(speed)
        if length < 1e-6:
            return False
        self._ux = (x - px) / length
        self._uy = (y - py) / length
        self._tx, self._ty = x, y
        self._x0, self._y0 = px, py
        self._len, self._s, self._v = length, 0.0, 0.0
        self._steps = 0
        self._done = done
        self._open = False
        self.mode = _LINEAR
        return True

    def turn_by(self, delta: float, done: Done, rate: float = _INF) -> bool:
        """Turn in place by ``delta`` radians (counter-clockwise positive), no faster than
        ``rate`` (rad/s), if that is below the robot's."""
        self._halt()
        if abs(delta) < 1e-9:
            return False
        self._wtop = min(self._wmax, rate)
        self._ta = self.robot_angle() + delta
        self._ta_offset = self._sway_offset
        self._ux = 1.0 if delta > 0 else -1.0
        self._len, self._s, self._v = abs(delta), 0.0, 0.0
        self._done = done
        self.mode = _ANGULAR
        return True

    def command(self, v: float, w: float) -> None:
        """Wanted forward speed (m/s) and turning rate (rad/s), within the limits."""
        v = max(-self._vmax, min(self._vmax, v)) if abs(v) >= STILL else 0.0
        w = max(-self._wmax, min(self._wmax, w)) if abs(w) >= STILL else 0.0
        if self.mode != _VELOCITY:
            if v == 0.0 and w == 0.0 and self.mode == _IDLE:
                return  # (still, and asked to stay so)
            self._halt()
            self._v = self._w = 0.0
            self.mode = _VELOCITY
        self._cmd_v, self._cmd_w = v, w

    def stop(self, stopped: Callable[[], None] | None = None) -> bool:
        """Brake to a standstill; ``stopped`` is called when still. False if already still."""
        if self.mode == _IDLE:
            return False
        if self.mode != _VELOCITY:
            # profiles brake by abandoning the profile at the current speed
            v = self._v
            lin = self.mode == _LINEAR
            ux = self._ux
            self._halt()
            self.mode = _VELOCITY
            body = self.robot
            if lin:
                self._v, self._w = v, 0.0
                body.velocity = (math.cos(body.angle) * v, math.sin(body.angle) * v)
            else:
                self._v, self._w = 0.0, v * ux
                body.angular_velocity = v * ux  # (the body keeps its speed as it brakes)
        self._cmd_v = self._cmd_w = 0.0
        self._still = None
        if stopped is not None:
            self._on_stopped.append(stopped)
        return True

    def _halt(self) -> None:
        """Forget the current controller (the caller sets a new one). The body stops too,
        idle or not: a push (a user walking into it) leaves it no speed of its own."""
        self._sync()
        self._room = -1.0  # (kept for a velocity command's stretches: see _walls_far)
        rb = self._rb  # (``robot.velocity.length``, ``robot.angular_velocity``, read for less)
        if (self.mode != _IDLE or _length(_cpBodyGetVelocity(rb)) > 0.0
                or _cpBodyGetAngularVelocity(rb)):
            _cpBodySetVelocity(rb, (0.0, 0.0))
            _cpBodySetAngularVelocity(rb, 0.0)
            self._still = None
        self.mode = _IDLE
        self._done = None
        if self._cap != _INF:  # (a drive's own speed goes with it)
            self._capped(_INF)

    # ---- stepping ------------------------------------------------------------

    def step(self) -> Callable[[], None] | None:
        """Advance one fixed step if anything moves (:meth:`run` a stretch of one);
        returns a callback if a motion just ended."""
        return self.run(0, 1)[1]

    def run(self, tick: int, bound: int) -> tuple[int, Callable[[], None] | None]:
        """Step from the tick ``tick`` on while anything moves (a drive, a turn, a sway,
        the user walking, a joint before :attr:`joints_until`), up to the tick ``bound``
        or a step whose motion ended (its callback, as :meth:`step` returns it).
        Returns the tick reached and that callback: where the simulator looks at its
        agenda and senses next, it stops (a run takes thousands of steps)."""
        while True:  # (a loop of the controller's own for each stretch)
            sway = self._sway
            advance: Callable[[object, float], None] = (
                _cpSpaceStep if sway is None else self._advance)
            mode = self.mode
            if mode == _IDLE:
                if self.human_moving:
                    end = bound
                else:  # (still, once the joints and the sway are done)
                    end = min(bound, max(self.joints_until,
                                         tick if sway is None else tick + sway[2] - self._sway_k))
                    if end <= tick:
                        return tick, None
                tick = self._run_idle(tick, end, advance)
                done = None
            elif mode == _LINEAR:
                tick, done = self._run_linear(tick, bound, advance)
            elif mode == _ANGULAR:
                tick, done = self._run_angular(tick, bound, advance)
            else:
                tick, done = self._run_velocity(tick, bound, advance)
            if done is not None or tick >= bound:
                return tick, done

    def _run_idle(self, tick: int, end: int, advance: Callable[[object, float], None]) -> int:
        """Idle steps up to the tick ``end``, the first and each one that touched
        something (a push) followed by :meth:`_hold`; worked out without Chipmunk if they
        can be (:meth:`_glides`)."""
        n = end - tick
        version = self.version
        if self._glides(n):
            self._glided(version, n)
            if self._ak == version:
                self._ak = version + n  # (idle, it faces the same way)
            return end
        self._sync()
        space, dt, touched = self._sp, self.dt, self._touched
        touched[0] = False
        advance(space, dt)
        calm = 0 if touched[0] else self._calm + 1
        self._hold()  # (the first step is checked)
        for _ in range(n - 1):
            advance(space, dt)
            if touched[0]:
                calm = 0
                self._hold()
            else:
                calm += 1
        self._calm = calm
        self.version = version + n
        return end

    def _glides(self, n: int) -> bool:
        """Whether the next ``n`` steps, idle or turning in place, can be worked out
        without Chipmunk (:meth:`_glide_user`), to the last bit what its steps would
        give. They can if nothing can touch the robot in them: it has touched nothing
        for Chipmunk's collision persistence (so Chipmunk keeps no contact of its, and
        no push left it a speed of its own: its velocity, read once in a calm, is
        nought), nothing sways it, and the user cannot come within reach in ``n`` steps.
        A step then only turns the robot by its turning rate and moves the user on by
        their velocity, as Chipmunk's position update does: ``p + (v + 0) * dt``."""
        if self._calm < self._persist or self._sway is not None:
            return False
        still = self._still
        if still is None:
            v = _cpBodyGetVelocity(self._rb)
            still = self._still = v.x == 0.0 and v.y == 0.0
        if not still:
            return False
        if self._pk != self.version:
            self._read()
        if not self.human_moving:
            return True
        rx, ry = self._rxy
        ux, uy = self._hxy
        vx, vy = self._hv
        return _hypot(ux - rx, uy - ry) - _hypot(vx, vy) * (n * self.dt) > self._reach

    def _glided(self, version: int, n: int) -> None:
        """``n`` steps from the version ``version`` were worked out without Chipmunk
        (:meth:`_glides`): the user moves on, the version too, and the poses read at it
        (:meth:`_glides` reads them) stay read: the robot stands where it was."""
        self.glided += n
        self._glide_user(n)
        self.version = version + n
        self._hxy = (self._lx, self._ly) if self._lazy else self._hxy
        self._pk = version + n

    def _glide_user(self, n: int) -> None:
        """Move the user on by ``n`` steps as Chipmunk would (:meth:`_glides`), kept in
        ``_lx``, ``_ly`` until a real step or the bodies need it in Chipmunk
        (:meth:`_sync`). A user who stands stays where Chipmunk has them."""
        if not self.human_moving:
            return
        if not self._lazy:
            h = _cpBodyGetPosition(self._hb)
            self._lx, self._ly = h.x, h.y
            self._lazy = True
        vx, vy = self._hv
        dx, dy = (vx + 0.0) * self.dt, (vy + 0.0) * self.dt
        x, y = self._lx, self._ly
        for _ in range(n):
            x += dx
            y += dy
        self._lx, self._ly = x, y

    def _run_linear(self, tick: int, bound: int, advance: Callable[[object, float], None]
                    ) -> tuple[int, Callable[[], None] | None]:
        """Straight-drive steps up to the tick ``bound`` or the drive's end: each speeds
        up, cruises or brakes (whichever is slowest), so as to stop at the end, and sets
        the body's velocity along the line again if a push set it off.

        The push check reads the body's speed only before a stretch's first step and
        after a step that touched something (:attr:`_touched`): every other step leaves
        it the speed the one before set. A stretch cruising all along (:meth:`_cruising`)
        leaves only the push check and the lag check to each step.

        Where nothing can touch the robot in the stretch (:meth:`_glides_straight`), its
        steps are worked out without Chipmunk instead (:meth:`_glide_linear`)."""
        self._still = None
        if self._glides_straight(bound - tick):
            return self._glide_linear(tick, bound)
        self._sync()
        calm = before = self._calm
        dt, rb, space, vmax = self.dt, self._rb, self._sp, self._vmax
        length, s, v, steps = self._len, self._s, self._v, self._steps
        touched = self._touched
        touched[0] = True  # (the first step is checked)
        twice = 2.0 * self.spec.max_accel
        start = tick
        last = blocked = False
        ds = vmax * dt
        if self._cruising(tick, bound):
            vx, vy = self._ux * vmax, self._uy * vmax
            while tick < bound:
                if touched[0] and self._pushed(vx, vy):
                    v = vmax
                advance(space, dt)
                calm = 0 if touched[0] else calm + 1
                s += ds
                tick += 1
                steps += 1
                if steps % _CHECK_EVERY == 0 and self._lagging(s):
                    blocked = True
                    break
        else:
            a_dt, ux, uy = self._a_dt, self._ux, self._uy
            while True:
                rem = length - s
                # (a min of two, twice: compiled, a min of two numbers is a comparison, of
                # three a call of the builtin on boxed floats, some 750 instructions a step)
                nv = min(min(vmax, v + a_dt), math.sqrt(twice * rem))
                last = nv * dt >= rem
                if last:
                    nv = rem / dt
                vx, vy = ux * nv, uy * nv
                if nv != v:
                    _cpBodySetVelocity(rb, (vx, vy))
                    v = nv
                    touched[0] = False
                elif touched[0]:
                    self._pushed(vx, vy)
                advance(space, dt)
                calm = 0 if touched[0] else calm + 1
                s += nv * dt
                tick += 1
                if last:
                    break
                steps += 1
                if steps % _CHECK_EVERY == 0 and self._lagging(s):
                    blocked = True
                    break
                if tick >= bound:
                    break
        self._s, self._v, self._steps = s, v, steps
        self._calm = calm
        if calm != before + (tick - start):
            self._open = False  # (pushed: maybe off the line its path was asked for)
        done = self._end_linear(last, blocked)
        self.version += tick - start  # (after the end's snap: see the module's doc)
        return tick, done

    def _end_linear(self, last: bool, blocked: bool) -> Callable[[], None] | None:
        """A straight-drive stretch ended: the drive too if its last step was taken or it
        lags (blocked), the robot put at its goal if it got there (a pose written: the
        calm starts again)."""
        if last:
            self._calm = 0
            return self._finish_linear()
        if blocked:
            self._calm = 0
            return self._finish(False)  # someone or something in the way
        return None

    def _glides_straight(self, n: int) -> bool:
        """Whether the next ``n`` steps of the straight drive can be worked out without
        Chipmunk (:meth:`_glide_linear`), as :meth:`_glides` asks it of an idle robot: it
        has touched nothing for Chipmunk's collision persistence (its velocity is then the
        one the drive set: nothing else changes it), nothing sways it, no wall is within
        reach of the rest of its path (:attr:`_open`), and the user cannot come within
        reach in ``n`` steps, both moving at their fastest. Its turning rate is nought (a
        straight drive starts from :meth:`_halt`), so its steps only move it."""
        if self._calm < self._persist or self._sway is not None or n <= 0:
            return False
        if self._pk != self.version:
            self._read()
        rx, ry = self._rxy
        if not self._open:
            rest = self._len - self._s
            end = (rx + self._ux * rest, ry + self._uy * rest)
            self._open = self._clear((rx, ry), end, self.spec.radius + _GLIDE_MARGIN)
            if not self._open:
                return False
        ux, uy = self._hxy
        speed = max(self._v, self._vmax)
        if self.human_moving:
            speed += _hypot(*self._hv)
        return _hypot(ux - rx, uy - ry) - speed * (n * self.dt) > self._reach

    def _glide_linear(self, tick: int, bound: int) -> tuple[int, Callable[[], None] | None]:
        """The steps of :meth:`_run_linear` up to the tick ``bound`` or the drive's end,
        worked out without Chipmunk (:meth:`_glides_straight`): each sets the speed as a
        step there does, and moves the robot on as Chipmunk's position update does
        (``p + (v + 0) * dt``, from the velocity the step set: ``(ux * v, uy * v)``), the
        user too (:meth:`_glide_user`). The robot's position is kept in Python until a
        real step or the bodies need it (:meth:`_sync`); its velocity is written to
        Chipmunk as its next step would leave it (``v + 0``)."""
        dt, vmax, a_dt = self.dt, self._vmax, self._a_dt
        length, s, v, steps = self._len, self._s, self._v, self._steps
        ux, uy = self._ux, self._uy
        twice = 2.0 * self.spec.max_accel
        x, y = self._rxy
        version, start, first = self.version, tick, v
        last = blocked = False
        if self._cruising(tick, bound):  # (each step the same: as in _run_linear)
            dx, dy, ds = (ux * vmax + 0.0) * dt, (uy * vmax + 0.0) * dt, vmax * dt
            while tick < bound:
                x += dx
                y += dy
                s += ds
                tick += 1
                steps += 1
                if steps % _CHECK_EVERY == 0 and self._lags(s, x, y):
                    blocked = True
                    break
        while not (last or blocked or tick >= bound):
            rem = length - s
            nv = min(min(vmax, v + a_dt), math.sqrt(twice * rem))  # (as _run_linear's)
            last = nv * dt >= rem
            if last:
                nv = rem / dt
            v = nv
            x += (ux * nv + 0.0) * dt
            y += (uy * nv + 0.0) * dt
            s += nv * dt
            tick += 1
            if not last:
                steps += 1
                blocked = steps % _CHECK_EVERY == 0 and self._lags(s, x, y)
        self._s, self._v, self._steps = s, v, steps
        vx, vy = ux * v, uy * v
        if v != first or vx == 0.0 or vy == 0.0:  # (a step leaves a -0.0 as 0.0)
            _cpBodySetVelocity(self._rb, (vx + 0.0, vy + 0.0))
        self._rx, self._ry, self._rlazy = x, y, True
        self._rxy = (x, y)
        self._glided(version, tick - start)
        if self._ak == version:
            self._ak = version + (tick - start)  # (it turns not: see _glides_straight)
        if not (last or blocked):
            return tick, None
        self._sync()
        done = self._end_linear(last, blocked)
        self._pk = -1  # (the robot may be put at its goal: read afresh)
        return tick, done

    def _cruising(self, tick: int, bound: int) -> bool:
        """Whether the straight drive cruises at its top speed at every step from the tick
        ``tick`` up to ``bound``, far enough from its end to brake after. Then each step's
        speed is the top speed again (the first of the three in ``min``: the others, the
        speed plus a positive gain and the braking speed, are at least it), and it is not
        the last step. The rest of the drive left after ``bound``, less a margin far wider
        than the rounding of the progress's sums, passes the tests of the speed and of the
        last step: both grow with the rest, in floating point as in reals, and every
        step's rest is longer."""
        vmax = self._vmax
        if self._v != vmax:
            return False
        ds = vmax * self.dt
        low = self._len - self._s - (bound - tick) * ds - _MARGIN
        return ds < low and vmax <= math.sqrt(2.0 * self.spec.max_accel * low)

    def _pushed(self, vx: float, vy: float) -> bool:
        """After a step that touched something (or before a stretch's first): the body's
        velocity set back to (vx, vy) if a push changed it (off the drive's course);
        whether it did."""
        self._touched[0] = False
        now = _cpBodyGetVelocity(self._rb)
        if now.x != vx or now.y != vy:
            _cpBodySetVelocity(self._rb, (vx, vy))
            return True
        return False

    def _run_angular(self, tick: int, bound: int, advance: Callable[[object, float], None]
                     ) -> tuple[int, Callable[[], None] | None]:
        """Turning steps up to the tick ``bound`` or the turn's end, ramped as a straight
        drive's speed is, each followed by :meth:`_hold` if pushed (the wheels hold the
        body where it turns): the first and each one that touched something
        (:attr:`_touched`)."""
        dt, rb, space = self.dt, self._rb, self._sp
        wtop, alpha_dt, sense = self._wtop, self._alpha_dt, self._ux
        twice = 2.0 * _radians(self.spec.turn_accel)
        length, s, v = self._len, self._s, self._v
        start = tick
        version = self.version
        glide = self._glides(bound - tick)  # (then the steps turn ``a`` at ``rate``)
        a = self.robot_angle() if glide else 0.0
        rate = sense * v  # (the body's turning rate: what the last step or turn wrote)
        if not glide:
            self._sync()
        calm = self._calm
        touched = self._touched
        touched[0] = False
        first = True  # (the first step is checked)
        while True:
            rem = length - s
            w = min(min(wtop, v + alpha_dt), math.sqrt(twice * rem))  # (of two: _run_linear)
            last = w * dt >= rem
            if last:
                w = rem / dt
            if w != v:
                rate = sense * w
                if not glide:
                    _cpBodySetAngularVelocity(rb, rate)
                v = self._v = w  # (a sway turns on top of it)
            if glide:
                a += (rate + 0.0) * dt  # (Chipmunk's position update; see _glides)
            else:
                advance(space, dt)
                if touched[0] or first:
                    calm = 0 if touched[0] else calm + 1
                    first = False
                    self._hold()
                else:
                    calm += 1
            s += w * dt
            tick += 1
            if last or tick >= bound:
                break
        self._s, self._v, self._calm = s, v, calm
        done = None
        if glide and not last:
            _cpBodySetAngularVelocity(rb, rate)  # (what the steps left: Chipmunk's next
            _cpBodySetAngle(rb, a)               # step goes on from it)
        if last:
            _cpBodySetAngularVelocity(rb, 0.0)
            _cpBodySetAngle(rb, self._ta + self._sway_offset - self._ta_offset)
            done = self._finish(True)
        if glide:
            self._glided(version, tick - start)  # (after the final angle, as below)
        else:
            self.version += tick - start  # (after the final angle: see the module's doc)
        return tick, done

    def _hold(self) -> None:
        """After a step that touched something (or a stretch's first), idle or turning
        in place: the wheels hold the body where it is, a push (the user walking into it)
        leaves it no speed to drift on with (:meth:`_pushed`'s twin for a drive)."""
        self._touched[0] = False
        if _length(_cpBodyGetVelocity(self._rb)) > 1e-9:
            _cpBodySetVelocity(self._rb, (0.0, 0.0))
            self._still = None

    @property
    def swaying(self) -> bool:
        """A sway runs (the world must be stepped, whatever else is idle)."""
        return self._sway is not None

    def _run_velocity(self, tick: int, bound: int, advance: Callable[[object, float], None]
                      ) -> tuple[int, Callable[[], None] | None]:
        """Velocity-command steps up to the tick ``bound`` or the robot's standstill:
        the speed and the turning rate each go toward the command's, within the
        accelerations.

        Where nothing can touch the robot in the stretch (:meth:`_glides_free`), its
        steps are worked out without Chipmunk instead (:meth:`_glide_velocity`); the
        calm counts the steps of a stretch that touched nothing."""
        self._still = None
        travel = self._glides_free(bound - tick)
        if travel >= 0.0:
            return self._glide_velocity(tick, bound, travel)
        self._sync()
        self._room = -1.0  # (it may touch a wall: asked again after)
        touched = self._touched
        touched[0] = False
        dt, rb, space = self.dt, self._rb, self._sp
        a, al = self._a_dt, self._alpha_dt
        cmd_v, cmd_w = self._cmd_v, self._cmd_w
        v, w = self._v, self._w
        start = tick
        still = False
        while not still and tick < bound:
            nv, nw = _toward(v, cmd_v, a), _toward(w, cmd_w, al)
            if nv == v and nw == w and (nv != 0.0 or nw != 0.0 or cmd_v != 0.0 or cmd_w != 0.0):
                # a fixed point: every step up to ``bound`` is this one (it works its speeds
                # out from the same numbers; only a heading that turns moves the velocity)
                if nv != 0.0 and nw != 0.0:
                    for _ in range(bound - tick):
                        ang = _cpBodyGetAngle(rb)
                        _cpBodySetVelocity(rb, (math.cos(ang) * nv, math.sin(ang) * nv))
                        advance(space, dt)
                else:
                    for _ in range(bound - tick):
                        advance(space, dt)
                v, w, tick = nv, nw, bound
                break
            if nv != 0.0 and (nv != v or w != 0.0 or nw != w):
                ang = _cpBodyGetAngle(rb)
                _cpBodySetVelocity(rb, (math.cos(ang) * nv, math.sin(ang) * nv))
            elif nv == 0.0 and v != 0.0:
                _cpBodySetVelocity(rb, (0.0, 0.0))
            if nw != w:
                _cpBodySetAngularVelocity(rb, nw)
                self._w = nw  # (a sway turns on top of it)
            v, w = nv, nw
            advance(space, dt)
            tick += 1
            still = nv == 0.0 and nw == 0.0 and cmd_v == 0.0 and cmd_w == 0.0
        self._v, self._w = v, w
        self._calm = 0 if touched[0] else self._calm + (tick - start)
        self.version += tick - start
        return tick, self._stopped() if still else None

    def _glides_free(self, n: int) -> float:
        """Whether the next ``n`` steps of the velocity command can be worked out without
        Chipmunk (:meth:`_glide_velocity`), as :meth:`_glides` asks it of an idle robot:
        it has touched nothing for Chipmunk's collision persistence (its velocity and
        turning rate are then the ones the command set), nothing sways it, and neither a
        wall (:meth:`_walls_far`) nor the user can come within reach in ``n`` steps, the
        robot at the fastest of its speed, the command's (it goes from one to the other)
        and its body's (a push may have left it another), the user at theirs. The
        farthest the robot can go in them (m), or -1.0 if they cannot."""
        if self._calm < self._persist or self._sway is not None or n <= 0:
            return -1.0
        self._adopt()
        if self._pk != self.version:
            self._read()
        rx, ry = self._rxy
        span = n * self.dt
        travel = max(abs(self._v), abs(self._cmd_v), _hypot(self._rvx, self._rvy)) * span
        if travel >= self._room and not self._walls_far(rx, ry, travel):
            return -1.0
        ux, uy = self._hxy
        near = _hypot(*self._hv) * span if self.human_moving else 0.0
        return travel if _hypot(ux - rx, uy - ry) - travel - near > self._reach else -1.0

    def _glide_steady(self, pose: tuple[float, float, float, float, float], wb: float,
                      v: float, n: int) -> tuple[float, float, float, float, float]:
        """``n`` steps of a velocity command at its fixed point (speed ``v``, turning rate
        ``wb``), from ``pose`` (position, heading, velocity), worked out as
        :meth:`_glide_velocity` works out each: the pose they leave. Only a heading that
        turns moves the velocity (set along it at every step, as in :meth:`_run_velocity`)."""
        x, y, ang, vx, vy = pose
        dt = self.dt
        da = (wb + 0.0) * dt
        if v != 0.0 and wb != 0.0:
            for _ in range(n):
                vx, vy = math.cos(ang) * v, math.sin(ang) * v
                x += (vx + 0.0) * dt
                y += (vy + 0.0) * dt
                ang += da
        else:
            dx, dy = (vx + 0.0) * dt, (vy + 0.0) * dt
            for _ in range(n):
                x += dx
                y += dy
                ang += da
        return x, y, ang, vx, vy

    def _adopt(self) -> None:
        """Keep the robot's heading, velocity and turning rate in Python
        (:attr:`_rvlazy`), read from Chipmunk if they are not kept already."""
        if not self._rvlazy:
            rb = self._rb
            body = _cpBodyGetVelocity(rb)
            self._rang, self._rvx, self._rvy = self.robot_angle(), body.x, body.y
            self._rw = float(_cpBodyGetAngularVelocity(rb))
            self._rvlazy = True

    def _walls_far(self, x: float, y: float, travel: float) -> bool:
        """Whether no wall comes within reach of the robot (its radius and
        :data:`_GLIDE_MARGIN`) as it moves up to ``travel`` (m) from (x, y), any way. Chipmunk
        is asked for the nearest wall up to :data:`_ROOM` farther: the room found
        (:attr:`_room`) serves the stretches after, each taking what it may travel."""
        reach = self.spec.radius + _GLIDE_MARGIN
        look = travel + _ROOM
        hit = _cpSpacePointQueryNearest(self._sp, (x, y), reach + look, _SIGHT, _NEAREST)
        self._room = look if hit == _NULL else float(_NEAREST.distance) - reach
        return travel < self._room

    def _glide_velocity(self, tick: int, bound: int, travel: float
                        ) -> tuple[int, Callable[[], None] | None]:
        """The steps of :meth:`_run_velocity` up to the tick ``bound`` or the robot's
        standstill, worked out without Chipmunk (:meth:`_glides_free`; ``travel``: the
        farthest the robot can go in them): each sets the velocity and the turning rate as
        a step there does and moves the robot on as Chipmunk's position update does
        (``p + (v + 0) * dt``, ``a + (w + 0) * dt``), the user too (:meth:`_glide_user`).
        The robot's pose, velocity and turning rate are kept in Python until a real step
        or the bodies need them (:meth:`_sync`), as its steps leave them (``v + 0``)."""
        dt, a_dt, al = self.dt, self._a_dt, self._alpha_dt
        cmd_v, cmd_w = self._cmd_v, self._cmd_w
        v, w = self._v, self._w
        x, y = self._rxy
        ang, vx, vy, wb = self._rang, self._rvx, self._rvy, self._rw  # (_glides_free: kept)
        version, start = self.version, tick
        still = False
        while not still and tick < bound:
            nv, nw = _toward(v, cmd_v, a_dt), _toward(w, cmd_w, al)  # (as _run_velocity's)
            if nv == v and nw == w and (nv != 0.0 or nw != 0.0 or cmd_v != 0.0 or cmd_w != 0.0):
                # a fixed point, as in _run_velocity: every step up to ``bound`` is this one
                x, y, ang, vx, vy = self._glide_steady((x, y, ang, vx, vy), wb, nv, bound - tick)
                tick = bound
                break
            if nv != 0.0 and (nv != v or w != 0.0 or nw != w):
                vx, vy = math.cos(ang) * nv, math.sin(ang) * nv
            elif nv == 0.0 and v != 0.0:
                vx = vy = 0.0
            if nw != w:
                wb = nw
            v, w = nv, nw
            x += (vx + 0.0) * dt
            y += (vy + 0.0) * dt
            ang += (wb + 0.0) * dt
            tick += 1
            still = nv == 0.0 and nw == 0.0 and cmd_v == 0.0 and cmd_w == 0.0
        n = tick - start
        self._v, self._w, self._room = v, w, self._room - travel
        self._rang, self._rvx, self._rvy, self._rw = ang, vx + 0.0, vy + 0.0, wb + 0.0
        self._rx, self._ry, self._rxy = x, y, (x, y)
        self._rvlazy = self._rlazy = True
        self._glided(version, n)
        self._ra, self._ak = ang, version + n
        return tick, self._stopped() if still else None

    def _stopped(self) -> Callable[[], None] | None:
        """The velocity command has brought the robot to a standstill: idle; whoever
        waits for it (:meth:`stop`) is told."""
        self._sync()
        _cpBodySetVelocity(self._rb, (0.0, 0.0))
        self.mode = _IDLE
        waiting, self._on_stopped = self._on_stopped, []
        if not waiting:
            return None

        def report() -> None:
            for f in waiting:
                f()
        return report

    def _lagging(self, s: float) -> bool:
        """The drive is well behind its plan, ``s`` along it: the body does not get where
        it is driven."""
        p = _cpBodyGetPosition(self._rb)  # (afresh: the stretch has not moved the version on)
        return self._lags(s, p.x, p.y)

    def _lags(self, s: float, x: float, y: float) -> bool:
        """:meth:`_lagging` at the position (x, y). (The stretch keeps ``s`` itself.)"""
        made: float = (x - self._x0) * self._ux + (y - self._y0) * self._uy
        return s - made > _BLOCKED_LAG

    def _finish_linear(self) -> Callable[[], None] | None:
        rb = self._rb  # (Chipmunk's calls, as pymunk's properties make them)
        _cpBodySetVelocity(rb, (0.0, 0.0))
        p = _cpBodyGetPosition(rb)
        arrived = _hypot(p.x - self._tx, p.y - self._ty) < 0.05
        if arrived:
            _cpBodySetPosition(rb, (self._tx, self._ty))
        return self._finish(arrived)

    def _finish(self, arrived: bool) -> Callable[[], None] | None:
        done = self._done
        self.mode = _IDLE
        self._done = None
        self._v = 0.0
        if self._cap != _INF:  # (as in _halt)
            self._capped(_INF)
        waiting, self._on_stopped = self._on_stopped, []
        if done is None and not waiting:
            return None

        def report() -> None:
            if done is not None:
                done(arrived)
            for f in waiting:
                f()
        return report
