"""Terrain and VR scenes for the capstan platform: a terrain profile along the walking path, a
walking speed, compliant patches, and who walks.

A scene file (TOML) looks like::

    name = "hill walk"
    walking_speed_m_s = 1.0
    person = "standing"            # seated, standing or walking (stepping in place)
    voluntary_torque_rms_nm = 2.0  # the person also pushes (0.1-3 Hz), default 2 N·m rms

    [[terrain]]                    # segments laid end to end from the start of the path
    kind = "flat"
    length_m = 2.0

    [[terrain]]
    kind = "slope"
    length_m = 6.0
    grade_deg = 8.0                # uphill positive

    [[terrain]]
    kind = "bumps"
    length_m = 4.0
    height_m = 0.004               # raised-cosine bumps this high ...
    spacing_m = 0.12               # ... this far apart

    [[compliant]]                  # optional soft ground, anywhere along the path
    start_m = 9.0
    length_m = 3.0
    stiffness_nm_per_rad = 60.0
    damping_nms_per_rad = 3.0

Segment kinds: ``flat``; ``slope`` (``grade_deg``); ``step`` (the ground rises by ``height_m``
at the segment's start, negative for a step down); ``bumps`` (``height_m``, ``spacing_m``);
``texture`` (random roughness of rms ``height_m`` with wavelengths from 2 cm to ``spacing_m``,
drawn with ``seed``). The foot of length ``foot_length_m`` rests on the ground at its heel and
toe: the platform's angle is ``atan((h(x + L/2) - h(x - L/2)) / L)`` at the ankle's position
``x``. Flat ground, slopes and steps make the *slope* component, bumps and texture the *bumps*
component; compliant patches are rendered by admittance about the terrain's angle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from anklelab._params import Parameters, parameters_from_mapping, read_parameter_document
from anklelab.errors import ParameterError

__all__ = [
    "CompliantPatch",
    "Scene",
    "SceneProfile",
    "TerrainSegment",
    "load_scene",
    "scene_profile",
]

SLOPE_KINDS = ("flat", "slope", "step")
TEXTURE_SHORTEST_M = 0.02


class TerrainSegment(Parameters):
    """One stretch of the path (see the module notes for the kinds)."""

    kind: Literal["flat", "slope", "step", "bumps", "texture"]
    length_m: float = Field(gt=0, le=1000, allow_inf_nan=False)
    grade_deg: float = Field(default=0.0, ge=-40, le=40, allow_inf_nan=False)
    height_m: float = Field(default=0.0, ge=-0.3, le=0.3, allow_inf_nan=False)
    spacing_m: float = Field(default=0.5, gt=TEXTURE_SHORTEST_M, le=10, allow_inf_nan=False)
    seed: int = Field(default=0, ge=0)

    @model_validator(mode="after")
    def _needs(self) -> TerrainSegment:
        needs = {"slope": "grade_deg", "step": "height_m", "bumps": "height_m"}
        needs["texture"] = "height_m"
        key = needs.get(self.kind)
        if key is not None and getattr(self, key) == 0.0:
            raise ParameterError(f"terrain: a {self.kind!r} segment needs a nonzero {key}")
        if self.kind == "texture" and self.height_m < 0:
            raise ParameterError("terrain: a 'texture' segment's height_m is an rms, >= 0")
        return self


class CompliantPatch(Parameters):
    """Soft ground between ``start_m`` and ``start_m + length_m``, rendered by admittance."""

    start_m: float = Field(ge=0, allow_inf_nan=False)
    length_m: float = Field(gt=0, allow_inf_nan=False)
    stiffness_nm_per_rad: float = Field(gt=0, le=1e4, allow_inf_nan=False)
    damping_nms_per_rad: float = Field(ge=0, le=100, allow_inf_nan=False)
    inertia_kgm2: float = Field(default=0.2, ge=0.1, le=5, allow_inf_nan=False)


class Scene(Parameters):
    """A terrain walk for the platform (see the module notes)."""

    name: str = Field(min_length=1, max_length=200)
    walking_speed_m_s: float = Field(gt=0, le=3, allow_inf_nan=False)
    foot_length_m: float = Field(default=0.25, ge=0.1, le=0.4, allow_inf_nan=False)
    person: Literal["seated", "standing", "walking"] = "standing"
    voluntary_torque_rms_nm: float = Field(default=2.0, ge=0, le=20, allow_inf_nan=False)
    terrain: tuple[TerrainSegment, ...] = Field(min_length=1, max_length=1000)
    compliant: tuple[CompliantPatch, ...] = Field(default=(), max_length=1000)

    @model_validator(mode="after")
    def _patches_on_path(self) -> Scene:
        end = sum(segment.length_m for segment in self.terrain)
        for k, patch in enumerate(self.compliant):
            if patch.start_m + patch.length_m > end:
                raise ParameterError(
                    f"compliant.{k}: ends at {patch.start_m + patch.length_m:g} m, beyond the "
                    f"path's end at {end:g} m"
                )
        return self

    @property
    def path_length_m(self) -> float:
        """Length of the path, m."""
        return float(sum(segment.length_m for segment in self.terrain))


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file; errors name the file and the key."""
    data = read_parameter_document(path, "toml", what="scene file")
    return parameters_from_mapping(Scene, data, origin=str(path))


@dataclass(frozen=True)
class SceneProfile:
    """The scene along time for a walk at the scene's speed.

    Attributes
    ----------
    time_s : ndarray
        Sample times, s.
    slope_rad, bumps_rad : ndarray
        The platform angle's slope and bumps components.
    stiffness_nm_per_rad, damping_nms_per_rad : ndarray
        Per sample: the patch's values, ``inf`` and 0 on rigid ground.
    inertia_kgm2 : float
        Virtual inertia of the patches (the largest asked for).
    patch : ndarray of int
        Index of the compliant patch under the ankle, -1 on rigid ground.
    """

    time_s: NDArray[np.float64]
    slope_rad: NDArray[np.float64]
    bumps_rad: NDArray[np.float64]
    stiffness_nm_per_rad: NDArray[np.float64]
    damping_nms_per_rad: NDArray[np.float64]
    inertia_kgm2: float
    patch: NDArray[np.int64]


def _heights(scene: Scene, x: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
    """Ground height of the slope part and of the bumps part at positions ``x`` (m)."""
    slope, bumps = np.zeros_like(x), np.zeros_like(x)
    start, level = 0.0, 0.0
    for seg in scene.terrain:
        inside = (x >= start) & (x < start + seg.length_m)
        beyond = x >= start + seg.length_m
        u = np.clip(x - start, 0.0, seg.length_m)
        if seg.kind == "slope":
            rise = math.tan(math.radians(seg.grade_deg))
            slope += np.where(inside | beyond, rise * u, 0.0)
            level += rise * seg.length_m
        elif seg.kind == "step":
            slope += np.where(inside | beyond, seg.height_m, 0.0)
            level += seg.height_m
        elif seg.kind == "bumps":
            bumps += np.where(
                inside, 0.5 * seg.height_m * (1 - np.cos(2 * np.pi * u / seg.spacing_m)), 0.0
            )
        elif seg.kind == "texture":
            rng = np.random.default_rng(seg.seed)
            waves = np.geomspace(TEXTURE_SHORTEST_M, seg.spacing_m, 24)
            phases = rng.uniform(0, 2 * np.pi, waves.size)
            rough = np.sin(2 * np.pi * u[:, None] / waves + phases).sum(axis=1)
            fade = np.minimum(u, seg.length_m - u) / (0.5 * seg.spacing_m)
            taper = np.clip(fade, 0.0, 1.0)
            bumps += np.where(inside, seg.height_m * rough * taper / math.sqrt(waves.size / 2), 0)
        start += seg.length_m
    return slope, bumps


def scene_profile(scene: Scene, fs: float, *, lead_s: float = 1.0) -> SceneProfile:
    """The scene in time at ``fs`` Hz, after ``lead_s`` standing at the start of the path.

    Examples
    --------
    >>> flat = TerrainSegment(kind="flat", length_m=1.0)
    >>> ramp = TerrainSegment(kind="slope", length_m=4.0, grade_deg=10.0)
    >>> scene = Scene(name="ramp", walking_speed_m_s=1.0, terrain=(flat, ramp))
    >>> p = scene_profile(scene, 100.0, lead_s=0.0)
    >>> round(math.degrees(p.slope_rad[300]), 2)         # 3 m along: on the 10 degree slope
    10.0
    """
    if not fs > 0 or not lead_s >= 0:
        raise ParameterError(f"fs must be > 0 and lead_s >= 0; got {fs}, {lead_s}")
    duration = lead_s + scene.path_length_m / scene.walking_speed_m_s
    t = np.arange(round(duration * fs)) / fs
    x = np.maximum(t - lead_s, 0.0) * scene.walking_speed_m_s
    half = 0.5 * scene.foot_length_m
    s_toe, b_toe = _heights(scene, x + half)
    s_heel, b_heel = _heights(scene, x - half)
    slope = np.arctan((s_toe - s_heel) / scene.foot_length_m)
    total = np.arctan((s_toe + b_toe - s_heel - b_heel) / scene.foot_length_m)
    patch = np.full(t.size, -1, dtype=np.int64)
    for k, p in enumerate(scene.compliant):
        patch[(x >= p.start_m) & (x < p.start_m + p.length_m) & (t >= lead_s)] = k
    stiffness = np.array([p.stiffness_nm_per_rad for p in scene.compliant] + [math.inf])[patch]
    damping = np.array([p.damping_nms_per_rad for p in scene.compliant] + [0.0])[patch]
    inertia = max((p.inertia_kgm2 for p in scene.compliant), default=0.2)
    return SceneProfile(t, slope, total - slope, stiffness, damping, inertia, patch)
