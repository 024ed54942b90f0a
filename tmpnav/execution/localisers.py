"""Who localises the simulated robots of ``tmpnav simulate``: the choice, in one place.

Two localisers execute a plan, behind one small interface (:class:`Localiser`), the way nav2
keeps its localiser a plugin:

* ``ekf`` (the default): tmpnav's own joint EKF (:mod:`tmpnav.belief.ekf`, the filterpy
  reference) with the landmarks, the range scans and the mutual observations of the planner's
  model. It checks the plan against the model it was made with.
* ``amcl``: nav2's AMCL (:mod:`tmpnav.execution.amcl`, the optional extra ``tmpnav[amcl]``),
  one particle filter per robot, fed with the simulator's odometry and the scans of a site
  that differs from the map (:mod:`tmpnav.execution.site`). It checks the plan against the
  localiser nav2 robots run: what the plan's beliefs must agree with.

:class:`Localisation` is what ``simulate`` and the closed loop pass to every
:class:`~tmpnav.execution.session.Session`; :data:`LOCALISERS` names the choices.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Protocol

import numpy as np

from tmpnav.execution.recovery import RecoveryParams
from tmpnav.execution.rpp import RppParams
from tmpnav.scenario.nav2_params import AmclParams

if TYPE_CHECKING:  # the site (numba kernels) is imported only by the sessions that scan it
    from tmpnav.execution.site import SiteNoise
    from tmpnav.world import World
    from tmpnav.world.visibility import LandmarkVisibility

#: the localisers ``tmpnav simulate --localiser`` offers, and what each is
LOCALISERS = {
    "ekf": "tmpnav's joint EKF with the planner's own sensor models",
    "amcl": "nav2's AMCL (a particle filter per robot, its beam model) on scans of a site unlike the map",
}

#: what ``tmpnav simulate --steer`` lets the robots steer on, and what each is
STEERING = {
    "auto": "local with --localiser amcl, estimate with ekf",
    "local": "the estimate placed among the walls by the lidar's nearby returns (nav2's costmaps)",
    "estimate": "the localiser's estimate alone, against the map",
}
#: the controllers ``tmpnav simulate --follower`` offers, and what each is
FOLLOWERS = {
    "auto": "the plan's own controller (models.controller): rpp for rpp, waypoint for turn-then-drive",
    "waypoint": "turns on the spot at each node of the path, then drives straight (the plan's own motions)",
    "rpp": "nav2's Regulated Pure Pursuit: turns while it drives, slows at bends and near walls",
}


def substep_noise(alphas: np.ndarray, substeps: int) -> np.ndarray:
    """The motion noise's alphas (4,) for a prediction in ``substeps`` steps of dt / N, each of
    the noise W(u) of paper eq. (4) held for the whole step: N times W, so that the N
    independent steps add up to the position variance dt² W of the one step they make."""
    return np.asarray(alphas, dtype=float) * substeps


class Localiser(Protocol):
    """One robot's localiser fed by odometry and scans (``amcl``); the joint EKF is the session's own."""

    name: str

    def update(self, odom: np.ndarray, ranges: np.ndarray) -> bool:
        """Odometry pose (3,) and one scan's ranges (B,) m (nan: no return); whether the filter updated."""
        ...

    @property
    def mean(self) -> np.ndarray:
        """(3,) the pose estimate now."""
        ...

    @property
    def cov(self) -> np.ndarray:
        """(3, 3) the localiser's own covariance of its estimate."""
        ...


class TeamLocaliser(Protocol):
    """Who estimates the poses of a session's robots (:class:`~tmpnav.execution.session.Session`
    calls it once per control step): the joint EKF (:mod:`.joint_ekf`, its compiled twin
    :mod:`.fast_ekf`) or every robot's AMCL (:mod:`.amcl_team`)."""

    def estimate(self, i: int) -> np.ndarray:
        """Robot i's pose estimate (3,) now."""
        ...

    def estimate_cov(self, i: int) -> np.ndarray:
        """Robot i's covariance (3, 3) as its localiser reports it."""
        ...

    def predict(self, u: np.ndarray, steps: np.ndarray | None = None) -> None:
        """The commands (n, 2) of the control step just driven; with ``steps`` (n, N, 2), the
        commands each robot drove at its controller's rate, each held dt / N (``u`` their mean;
        a robot that held one command for the step has it N times): the prediction follows them
        one by one, as a robot's odometry does (:func:`substep_noise`)."""
        ...

    def observe(self, truth: np.ndarray, step: int) -> list[tuple[int, int]]:
        """The robots' observations at control ``step`` from their true poses (n, 3); per robot,
        the range beams used and rejected by an innovation gate."""
        ...

    def set_world(self, world: World, vis: LandmarkVisibility) -> None:
        """The world changed (a door closed)."""
        ...


@dataclass(frozen=True)
class Localisation:
    """How a simulation localises its robots: ``kind`` (a key of :data:`LOCALISERS`), AMCL's
    parameters (nav2's defaults or a nav2 params file), and how the site differs from the map
    (a :class:`tmpnav.execution.site.SiteNoise`; None: the map exactly)."""

    kind: str = "ekf"
    amcl: AmclParams = field(default_factory=AmclParams)
    site: SiteNoise | None = None
    #: who steers each robot along its moves (a key of :data:`FOLLOWERS`) and, for ``rpp``, nav2's
    #: Regulated Pure Pursuit parameters: the controller belongs to the same navigation stack
    follower: str = "auto"
    rpp: RppParams = field(default_factory=RppParams)
    #: ekf: the compiled joint EKF (tmpnav.execution.fast_ekf); False: its filterpy reference
    #: (tmpnav.execution.joint_ekf), the same figures to rounding, many times slower
    compiled: bool = True
    #: what the robots steer on (a key of :data:`STEERING`; ``auto``: ``local`` with AMCL, as nav2
    #: robots do, ``estimate`` with the EKF, as the plan's own model does)
    steer: str = "auto"
    #: with ``steers_local``: nav2's recovery behaviours when the controller cannot go on, with
    #: nav2's defaults (tmpnav.execution.recovery); False: the robot stands until its move's budget ends
    recoveries: bool = True
    recovery: RecoveryParams = field(default_factory=RecoveryParams)

    def following(self, controller: str) -> Localisation:
        """This localisation with ``auto`` resolved for a plan driven by ``controller``
        (models.controller): the waypoint follower for turn-then-drive plans; for RPP plans
        ``auto`` stays, each move followed as the plan drives it (:meth:`steers_rpp`)."""
        if self.follower != "auto" or controller == "rpp":
            return self
        return replace(self, follower="waypoint")

    def steers_rpp(self, controller: str) -> bool:
        """Whether a move the plan drives by ``controller`` is steered by RPP: always with
        ``--follower rpp``, never with ``waypoint``, as planned with ``auto`` (a plan made for RPP
        drives a move turn-then-drive where RPP would cut a corner into a door's frame)."""
        return self.follower == "rpp" or (self.follower == "auto" and controller == "rpp")

    @property
    def steers_local(self) -> bool:
        """The robots keep clear of the walls their lidar sees (tmpnav.execution.local_view)."""
        return self.steer == "local" or (self.steer == "auto" and self.particle_filter)

    @property
    def particle_filter(self) -> bool:
        """Each robot localises on its own with AMCL (no landmarks, no partners)."""
        return self.kind == "amcl"

    def describe(self, motion_noise: tuple[float, float, float, float]) -> str:
        """One line for reports: the executing localiser, the site and the true motion noise."""
        a1, a2, a3, a4 = motion_noise
        noise = f"true motion noise alpha1-4 {a1:g}, {a2:g}, {a3:g}, {a4:g}"
        if self.follower in ("rpp", "auto"):
            r = self.rpp
            noise += (
                f"; follower: nav2 Regulated Pure Pursuit (lookahead {r.lookahead_dist:g} m, "
                f"min radius {r.regulated_linear_scaling_min_radius:g} m, goal tolerance {r.xy_goal_tolerance:g} m)"
            )
            if self.follower == "auto":
                noise += ", the waypoint follower on the moves the plan drives turn-then-drive"
        noise += (
            "; steering on where the lidar places it among the walls (nav2's costmaps)"
            if self.steers_local
            else "; steering on the estimate alone"
        )
        if self.steers_local:
            noise += f", nav2's recoveries ({self.recovery.retries} retries)" if self.recoveries else ", no recoveries"
        if not self.particle_filter:
            return f"localiser: ekf ({LOCALISERS['ekf']}); {noise}"
        where = self.site.text() if self.site is not None else "the map exactly"
        p = self.amcl
        return (
            f"localiser: nav2 AMCL ({p.min_particles}-{p.max_particles} particles, sigma_hit {p.sigma_hit:g} m, "
            f"max_beams {p.max_beams}, alphas {p.alpha1:g}); site: {where}; {noise}"
        )
