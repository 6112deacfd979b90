"""wavepath: a physically based wavefront path tracer for the CPU.

Load a scene from a file or build one from numpy arrays, render it to a numpy image (the
command line's image, bit for bit, for the same settings), or cast rays at it from numpy
arrays. Long calls release the GIL; renders stop on Ctrl-C.

    import wavepath
    scene = wavepath.load("dragon.ply")          # or wavepath.Scene.from_arrays(v, f)
    image, stats = scene.render(spp=16, max_depth=5, resolution=(320, 240))
    hits = scene.intersect(origins, directions)  # {"t", "prim", "uv"}
"""

from os import PathLike
from typing import Any, Callable, Literal, Optional, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str

MISS: int
"""The primitive id of a ray that hits nothing (0xFFFFFFFF), as in ray-hit files."""

ArrayLike = npt.ArrayLike
Vec3 = Union[float, Sequence[float]]

class Hits(TypedDict, total=False):
    t: npt.NDArray[np.float32]
    """(n,) distance along the direction (in its units); inf on a miss."""
    prim: npt.NDArray[np.uint32]
    """(n,) triangle index in the file's order (spheres after triangles); MISS on a miss."""
    uv: npt.NDArray[np.float32]
    """(n, 2) barycentric coordinates of the hit in its triangle."""
    normal: npt.NDArray[np.float32]
    """(n, 3) unit geometric normal (only with normals=True)."""

class Rays(TypedDict):
    origins: npt.NDArray[np.float32]
    directions: npt.NDArray[np.float32]
    tmin: npt.NDArray[np.float32]
    tmax: npt.NDArray[np.float32]

def load(
    path: Union[str, PathLike[str]],
    *,
    camera: Optional[Literal["cs184", "file"]] = None,
    smooth_normals: Optional[bool] = None,
    two_sided_emission: Optional[bool] = None,
    subdivide: Optional[int] = None,
) -> Scene:
    """Loads a scene file (.dae, .obj, .ply, .gltf, .glb); options left out keep the
    library's defaults, which are the command line's.

    camera: "cs184" (default) places a .dae file's camera as the CS184 reference renderer does (the
    command line's default); "file" keeps the file's camera as written. smooth_normals:
    COLLADA files get area-weighted vertex normals. two_sided_emission: every emitter emits
    from both faces. subdivide: rounds of midpoint subdivision (4**n times the triangles).

    Raises FileNotFoundError for a missing file and ValueError, with the command line's
    one-line message naming the file, for a malformed one.
    """

def default_scene() -> Scene:
    """The embedded Cornell box with two spheres that `wavepath` renders given no file."""

class Scene:
    """Triangles and spheres, materials, lights and a camera; its BVH is built once, on the
    first query or render (or by build())."""

    @staticmethod
    def from_arrays(
        vertices: Any,
        faces: Optional[ArrayLike] = None,
        *,
        normals: Optional[ArrayLike] = None,
        uvs: Optional[ArrayLike] = None,
        material_ids: Optional[ArrayLike] = None,
        materials: Optional[list[dict[str, Any]]] = None,
        lights: Optional[list[dict[str, Any]]] = None,
        spheres: Optional[list[dict[str, Any]]] = None,
        camera: Optional[Union[dict[str, Any], str, PathLike[str]]] = None,
        name: Optional[str] = None,
    ) -> Scene:
        """A scene from arrays: vertices (n, 3) float32/float64, faces (m, 3) integers.

        Or pass one object with `vertices` and `faces` attributes (a trimesh mesh) alone.
        normals (n, 3), uvs (n, 2) per vertex; material_ids (m,) indices into materials.
        materials: dicts with a "type": {"type": "diffuse", "color": (r, g, b)},
        {"type": "emitter", "radiance": ...}, {"type": "mirror", "color": ...},
        {"type": "glass", "ior": 1.5, "color": ..., "roughness": 0},
        {"type": "metallic_roughness", "color": ..., "metallic": 0, "roughness": 0.5},
        {"type": "phong", "diffuse": ..., "specular": ..., "shininess": 32}; any type also
        takes "emission", "two_sided" (emit from both faces; default front only) and "name".
        lights: {"type": "point", "position", "intensity"}, {"type": "directional",
        "direction", "radiance"}, {"type": "spot", "position", "direction", "intensity",
        "angle" (full cone, degrees), "falloff"}, {"type": "area", "position", "direction",
        "size_x", "size_y", "radiance"}, {"type": "sky", "radiance"} (the upper hemisphere).
        spheres: {"center", "radius", "material"}. camera: {"eye", "target", "up", "fov"
        (vertical, degrees), "lens_radius", "focal_distance"} or a camera file; without one,
        a camera that frames the bounds. With no light and no emitter, the default sky lights
        the scene (as a bare OBJ file). Renders use the "standard" dialect's defaults.

        Raises ValueError (wrong shape or dtype, NaN, an index out of range, an unknown key).
        """

    def render(
        self,
        *,
        spp: Optional[int] = None,
        light_samples: Optional[int] = None,
        max_depth: Optional[int] = None,
        accumulate: Optional[bool] = None,
        resolution: Optional[Tuple[int, int]] = None,
        camera: Optional[Union[dict[str, Any], str, PathLike[str]]] = None,
        threads: Optional[int] = None,
        sampler: Optional[Literal["independent", "stratified", "sobol"]] = None,
        seed: Optional[int] = None,
        adaptive: Optional[Tuple[int, float]] = None,
        shading: Optional[Literal["normals", "direct", "global"]] = None,
        integrator: Optional[Literal["auto", "wavefront", "path", "recursive", "light", "bdpt", "vcm", "path+light"]] = None,
        hemisphere: Optional[bool] = None,
        mis: Optional[bool] = None,
        roulette: Optional[Literal["fixed", "throughput"]] = None,
        rr: Optional[float] = None,
        rr_depth: Optional[int] = None,
        isa: Optional[Literal["scalar", "sse", "avx2", "avx512"]] = None,
        fov: Optional[Literal["cs184", "frame"]] = None,
        lens_radius: Optional[float] = None,
        focal_distance: Optional[float] = None,
        light_paths: Optional[float] = None,
        aovs: Optional[Sequence[Literal["albedo", "normal", "depth", "position", "variance"]]] = None,
        denoise: bool = False,
        oidn: Optional[Union[str, PathLike[str]]] = None,
        progress: Optional[Callable[[int, int], Any]] = None,
    ) -> Union[
        Tuple[npt.NDArray[np.float32], dict[str, Any]],
        Tuple[npt.NDArray[np.float32], dict[str, Any], dict[str, npt.NDArray[np.float32]]],
    ]:
        """Renders; returns (image, stats), or (image, stats, aovs) when aovs is given.

        image: float32 (height, width, 3), linear radiance, top row first. stats: what
        `wavepath --stats` writes (rays, mrays_per_s, stages, effects, ...) plus "log", the
        summary lines the command line prints.

        Each option is the command-line flag of the same meaning (spp -s, light_samples -l,
        max_depth -m, accumulate -o (False: only bounce max_depth), resolution -r, threads -t (0 or None: all cores), --sampler, --seed,
        adaptive -a, --shading, --integrator, hemisphere -H, mis (False: --no-mis),
        --roulette, --rr, --rr-depth, --isa, --fov, lens_radius -b, focal_distance -d, light_paths --light-paths); left
        out, the command line's default for the scene stands. The same options give the same
        image, bit for bit, as the command line. camera replaces the scene's for this render.

        aovs (--aov): output variables by name, returned as a dict of float32 arrays, top row
        first: albedo, normal, position and variance (height, width, 3), depth (height, width).
        Albedo and normal are those of the first hit that is not a mirror or glass, depth and
        position of the first hit (zero where a pixel's rays hit nothing), variance the
        estimated variance of each pixel's mean. denoise (--denoise): the image denoised by
        Intel Open Image Denoise with the render's albedo and normal, loaded at run time from
        oidn (a library, a folder holding it) or from the installed pyoidn package
        (`pip install pyoidn`); RuntimeError in one line when neither is there.

        The GIL is released; Ctrl-C raises KeyboardInterrupt within a fraction of a second;
        progress(done, total) is called a few times a second with camera samples finished.
        """

    def intersect(
        self,
        origins: ArrayLike,
        directions: ArrayLike,
        tmin: Optional[ArrayLike] = None,
        tmax: Optional[ArrayLike] = None,
        *,
        normals: bool = False,
        threads: int = 0,
    ) -> Hits:
        """Closest hits: origins and directions (n, 3) float32 or float64 (C- or Fortran-
        ordered; directions need not be unit length), tmin/tmax numbers or (n,) arrays
        (default 0 and inf). Watertight (a ray through a shared edge or vertex hits one of its
        triangles), the hits of `wavepath rays trace` for the same rays. threads=0: all cores.
        Raises ValueError for a wrong shape or dtype or a ray with NaN, inf or zero direction."""

    def occluded(
        self,
        origins: ArrayLike,
        directions: ArrayLike,
        tmin: Optional[ArrayLike] = None,
        tmax: Optional[ArrayLike] = None,
        *,
        threads: int = 0,
    ) -> npt.NDArray[np.bool_]:
        """Whether anything lies on each ray between tmin and tmax: bool (n,)."""

    def build(self, *, threads: int = 0) -> dict[str, Any]:
        """Builds the BVH now; returns build_s, nodes, leaves, depth, sah_cost, bytes."""

    def primary_rays(self, width: int, height: int) -> Rays:
        """One camera ray per pixel centre (rows bottom-up): the peers' primary set."""

    def diffuse_rays(self, width: int, height: int, seed: int = 0) -> Rays:
        """One cosine-distributed bounce from each primary hit: the peers' diffuse set."""

    @property
    def vertices(self) -> npt.NDArray[np.float32]:
        """(n, 3) vertex positions (a copy)."""
    @property
    def faces(self) -> npt.NDArray[np.uint32]:
        """(m, 3) vertex indices per triangle, in the file's order (a copy)."""
    @property
    def name(self) -> str: ...
    @property
    def triangle_count(self) -> int: ...
    @property
    def sphere_count(self) -> int: ...
    @property
    def materials(self) -> list[str]:
        """Material names in index order."""
    @property
    def lights(self) -> list[str]:
        """Light kinds in order ("area", "point", "hemisphere", ...)."""
    @property
    def bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]: ...
    @property
    def dialect(self) -> Literal["cs184", "standard"]:
        """Whose defaults renders start from: the CS184 course's or the standard ones."""
