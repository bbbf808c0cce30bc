# Type stubs of the compiled module gradel.gradel (python/gradel_module.cpp), re-exported by the
# package `gradel`. Units are SI (m, s, kg, Pa). Checked against the module by
# python/tests/test_stubs.py (mypy's stubtest).
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

class InputError(ValueError):
    """Bad input (a file, a key, a value); the message names it."""

class _Metrics(TypedDict):
    time: float
    kinetic_energy: float
    elastic_energy: float
    gravity_energy: float
    linear_momentum: list[float]
    angular_momentum: list[float]
    max_stress: float  # [Pa] von Mises
    max_strain: float  # [-]
    max_penetration: float
    min_element_det: float
    removed_voxels: int  # carving since t = 0 (docs/carving.md, "Feedback")
    removed_volume: float  # [m^3]
    removed_mass: float  # [kg]
    removed_momentum: list[float]  # [kg m/s] the removed material's

def load_volume(
    path: str,
    *,
    format: Optional[str] = None,
    threshold: Optional[float] = None,
    range: Optional[Tuple[float, float]] = None,
    resolution: int = 64,
    dims: Optional[Tuple[int, int, int]] = None,
    type: Optional[str] = None,
    endian: str = "little",
    header_bytes: int = 0,
    model: int = 0,
) -> npt.NDArray[np.bool_]:
    """Reads a volume or mesh file (binvox, vox, nrrd, nifti, raw, obj, stl, ply) into a
    read-only boolean array [i, j, k] without copying it."""

_Scene = Union[str, os.PathLike[str], Dict[str, Any]]
# A keyframe: (t [s], position [m]), (t, position, velocity [m/s]) or a scene file's dict.
_Keyframe = Union[Tuple[float, Sequence[float]], Tuple[float, Sequence[float], Sequence[float]], Mapping[str, Any]]

def check_scene(scene: _Scene) -> None:
    """Reads and checks a scene (a file's path or a dict of its keys) with the scene reader,
    building nothing: InputError naming the key."""

class Body:
    """A binary voxel volume to simulate."""

    @staticmethod
    def from_array(voxels: npt.ArrayLike, *, voxel_size: float = 0.01) -> Body: ...
    @staticmethod
    def from_file(
        path: str,
        *,
        format: Optional[str] = None,
        threshold: Optional[float] = None,
        range: Optional[Tuple[float, float]] = None,
        resolution: int = 64,
        dims: Optional[Tuple[int, int, int]] = None,
        type: Optional[str] = None,
        endian: str = "little",
        header_bytes: int = 0,
        model: int = 0,
        voxel_size: float = 0.01,
        dim: int = 3,
    ) -> Body: ...
    @staticmethod
    def from_shape(shape: str, size: int, *, dim: int = 3, voxel_size: float = 0.01) -> Body: ...
    @property
    def voxels(self) -> npt.NDArray[np.bool_]: ...
    @property
    def dim(self) -> int: ...
    @property
    def voxel_size(self) -> float: ...
    @property
    def filled(self) -> int: ...

class Simulation:
    """A body built into a gradational layout and simulated (World)."""

    def __init__(
        self,
        body: Body,
        *,
        layout: str = "gradational",
        scaling: str = "consistent",
        youngs_modulus: float = ...,
        density: float = ...,
        k: float = ...,
        integrator: str = "symplectic",
        dt: Optional[float] = None,
        dt_fraction: float = ...,
        damping: float = ...,
        gravity: Sequence[float] = [0.0, -9.81, 0.0],
        threads: int = 1,
        position: Sequence[float] = [0.0, 0.0, 0.0],
        velocity: Sequence[float] = [0.0, 0.0, 0.0],
        domain_min: Optional[Sequence[float]] = None,
        domain_max: Optional[Sequence[float]] = None,
        restitution: float = ...,
        friction: float = ...,
        poisson_ratio: float = 0.0,
    ) -> None: ...
    @staticmethod
    def from_scene(scene: _Scene) -> Simulation:
        """The simulation of a scene: a JSON file's path (str or pathlib.Path) or a dict of the
        same keys (docs/scenes.md), read and checked by the scene reader."""
    def add_body(self, body: Optional[Body] = None, **kwargs: Any) -> int:
        """Adds a body before the first step; returns its index. A Body, or a scene's bodies[i]
        keys as keyword arguments: shape, size, grid, primitives, source, voxel_size, layout,
        position, velocity, name, material (dict) or scaling, youngs_modulus, density, k,
        poisson_ratio, regions."""
    def add_pin(
        self,
        min: Optional[Sequence[float]] = None,
        max: Optional[Sequence[float]] = None,
        *,
        mask: Optional[npt.ArrayLike] = None,
        boxes: Optional[Sequence[Tuple[Sequence[int], Sequence[int]]]] = None,
        offset: Optional[Sequence[int]] = None,
        body: int = 0,
        path: Optional[Sequence[_Keyframe]] = None,
    ) -> int:
        """Pins (anchors) the vertices of body `body` in the box [min, max] [m] or on the
        voxels of `mask` / `boxes`; `path`: their offset from rest over time. Returns the
        pin's index."""
    def carve_sphere(
        self, center: Sequence[float], radius: float, labels: Optional[Sequence[int]] = None
    ) -> int:
        """Removes every body's voxels whose deformed centres lie within `radius` [m] of
        `center` [m] (only those of region `labels`, if given); the bodies are laid out again.
        Returns the voxels removed."""
    def carve_cylinder(
        self,
        center: Sequence[float],
        axis: Sequence[float],
        radius: float,
        half_length: float,
        labels: Optional[Sequence[int]] = None,
    ) -> int:
        """Removes every body's voxels whose deformed centres lie in the solid cylinder of
        `radius` and `half_length` [m] (flat caps) about `center` [m] along `axis`; the bodies are
        laid out again. Returns the voxels removed."""
    def cut(
        self,
        center: Sequence[float],
        axes: Sequence[Sequence[float]],
        half_extents: Sequence[float],
        to: Optional[Sequence[float]] = None,
    ) -> int:
        """A blade's cut: the rectangle about `center` [m] (half extents along the two
        perpendicular `axes`), parked or moved to `to`, removes its one-voxel kerf from every
        body; a body cut in two becomes two bodies. Returns the voxels removed."""
    def remove_voxels(self, body: int, mask: npt.ArrayLike) -> int:
        """Removes the voxels of body `body` where `mask` (its grid's shape) is true. Returns
        the voxels removed."""
    def apply_force(
        self, vertex_indices: npt.ArrayLike, forces: npt.ArrayLike, *, body: Optional[int] = None
    ) -> None:
        """External forces [N] on vertices for every step of the next step()/advance_to() call."""
    @property
    def external_impulse(self) -> list[float]:
        """[N s] the impulse apply_force() gave the bodies since t = 0."""
    @property
    def external_work(self) -> float:
        """[J] the energy apply_force() gave the bodies since t = 0."""
    @property
    def num_pins(self) -> int: ...
    @property
    def pinned_vertices(self) -> List[int]: ...
    def add_manipulator(
        self,
        type: str = "sphere",
        *,
        radius: float = 0.02,
        position: Sequence[float] = [0.0, 0.0, 0.0],
        half_length: float = 0.05,
        axis: Union[str, Sequence[float]] = "z",
        restitution: float = 1.0,
        friction: float = 0.0,
        path: Optional[Sequence[_Keyframe]] = None,
    ) -> int: ...
    def move_manipulator(self, index: int, position: Sequence[float], velocity: Sequence[float] = [0.0, 0.0, 0.0]) -> None: ...
    def manipulator_force(self, index: int, *, average: bool = True) -> Tuple[list[float], list[float]]:
        """(force [N], torque [N m] about its centre) the body exerts on a manipulator: averaged over
        the last step()/advance_to() call, or (average=False) of its last step."""
    def wall_force(self, wall: str = "all", *, average: bool = True) -> Tuple[list[float], list[float]]:
        """(force [N], torque [N m] about the origin) the body exerts on the walls together
        (wall="all") or on one wall: "xmin", "xmax", "ymin", "ymax", "zmin", "zmax"."""
    @property
    def manipulator_positions(self) -> npt.NDArray[np.float64]: ...
    def step(self, n: int = 1) -> None: ...
    def advance_to(self, t: float, *, max_steps: int = ...) -> None: ...
    @property
    def time(self) -> float: ...
    @property
    def dt(self) -> float: ...
    @property
    def dt_rule(self) -> str:
        """Where dt came from: "given", "one frame (1/60 s)", or the rule (dt_period x dt_fraction) and its numbers."""
    @property
    def integrator(self) -> str:
        """The integrator that runs (what "auto" resolved to)."""
    @property
    def integrator_choice(self) -> str:
        """Why "auto" picked the integrator (empty when the integrator was named)."""
    @property
    def num_vertices(self) -> int: ...
    @property
    def num_elements(self) -> int: ...
    @property
    def positions(self) -> npt.NDArray[np.float64]:
        """(N, 3) float64 view of the vertex positions [m] (no copy, writable)."""
    @property
    def velocities(self) -> npt.NDArray[np.float64]:
        """(N, 3) float64 view of the vertex velocities [m/s] (no copy, writable)."""
    @property
    def rest_positions(self) -> npt.NDArray[np.float64]: ...
    @property
    def masses(self) -> npt.NDArray[np.float64]: ...
    @property
    def stress(self) -> npt.NDArray[np.float64]:
        """Per-vertex von Mises stress [Pa] (mean of its elements')."""
    @property
    def element_stress(self) -> npt.NDArray[np.float64]:
        """Per-element von Mises stress [Pa] from the element's strain and its region's E and nu."""
    @property
    def strain(self) -> npt.NDArray[np.float64]:
        """Per-vertex strain measure [-] (the paper's fig. 1 measure)."""
    @property
    def element_strain(self) -> npt.NDArray[np.float64]:
        """Per-element strain measure [-]: RMS of |M R0_i - r_i| over the element's size."""
    @property
    def state_hash(self) -> int: ...
    @property
    def voxels(self) -> npt.NDArray[np.bool_]: ...
    def metrics(self) -> _Metrics: ...
    def body_metrics(self) -> List[_Metrics]:
        """metrics() per body (body order); metrics() is their sum."""
    @property
    def num_bodies(self) -> int: ...
    @property
    def body_names(self) -> List[str]: ...
    @property
    def body_vertex_ranges(self) -> List[Tuple[int, int]]:
        """Per body, (begin, end): its rows of positions, velocities, masses."""
    @property
    def body_element_ranges(self) -> List[Tuple[int, int]]: ...
    def body_positions(self, body: int) -> npt.NDArray[np.float64]:
        """(n, 3) view of one body's rows of positions (no copy, writable)."""
    def body_velocities(self, body: int) -> npt.NDArray[np.float64]: ...
    def surface(
        self, kind: str = "smooth", body: int = 0
    ) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.uint32], npt.NDArray[np.float64]]: ...
