"""A triangle mesh ready for ray casting: Open3D's RaycastingScene plus per-triangle data."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from wbsa.errors import WbsaError
from wbsa.core.mesh import TriangleMesh

#: Unit cube corners, used for the 8 corners of the mesh's bounding box.
_CORNERS = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=np.float64)


class MeshScene:
    """A triangle mesh ready for ray casting: Open3D BVH plus per-triangle areas and normals.

    Parameters
    ----------
    mesh : TriangleMesh
        Vertices in metres; at least one triangle with non-zero area, finite coordinates.
    nthreads : int
        Threads Open3D may use per cast (0 = all cores). Use 1 when many processes cast in parallel.
    surroundings : bool
        The mesh is a scene the camera stands in (a room with its floor and walls), not a body it must
        stay outside: the camera-inside-the-body check (:meth:`contains`) is off.

    Attributes
    ----------
    mesh : TriangleMesh
    triangle_areas_m2 : (m,) float64
    face_normals : (m, 3) float64
        Unit normals by the right-hand rule of each face's vertex order (zero for degenerate faces).
    one_sided : bool
        True for a consistently oriented, (nearly) closed surface: then only triangles facing the camera
        can be visible, which halves the object-space visibility tests of the visible-area estimate.
    orientation_sign : float
        +1 or −1: ``orientation_sign * face_normals`` point outward (+1 when ``one_sided`` is False).
    centroids : (m, 3) float64
    longest_edges_m : (m,) float64
        Longest edge of each triangle; ``max_edge_m`` is the largest of them.
    bbox_corners : (8, 3) float64
    bbox_min, bbox_max : (3,) float64
    center : (3,) float64
        Bounding-box centre, the subject's centre for the camera.
    """

    def __init__(self, mesh: TriangleMesh, nthreads: int = 0, *, surroundings: bool = False) -> None:
        import open3d as o3d

        mesh = TriangleMesh.from_any(mesh)  # also a trimesh or Open3D mesh, or a (vertices, faces) pair
        vertices, faces = validate_mesh(mesh)
        self.mesh = mesh
        self.nthreads = int(nthreads)
        self.surroundings = bool(surroundings)
        v0, v1, v2 = (vertices[f] for f in faces.T)
        e01, e20 = v1 - v0, v0 - v2
        cross = np.cross(e01, -e20)
        doubled = np.sqrt(np.einsum("ij,ij->i", cross, cross))
        self.triangle_areas_m2 = 0.5 * doubled  # paper eq. 4
        if not self.triangle_areas_m2.sum() > 0:
            raise WbsaError("the mesh has zero surface area (all triangles are degenerate); check the mesh file")
        self.face_normals = np.divide(cross, doubled[:, None], out=np.zeros_like(cross), where=doubled[:, None] > 0)
        self.bbox_min = vertices.min(axis=0)
        self.bbox_max = vertices.max(axis=0)
        self.center = 0.5 * (self.bbox_min + self.bbox_max)
        self.bbox_corners = self.bbox_min + _CORNERS * (self.bbox_max - self.bbox_min)
        self.centroids = (v0 + v1 + v2) / 3.0
        e12 = v2 - v1
        self.longest_edges_m = np.sqrt(np.maximum(np.maximum(np.einsum("ij,ij->i", e01, e01),
                                                             np.einsum("ij,ij->i", e12, e12)),
                                                  np.einsum("ij,ij->i", e20, e20)))
        self.max_edge_m = float(self.longest_edges_m.max())
        local = self.centroids - self.center
        self.one_sided, sign = _orientation(faces, vertices.shape[0], self.triangle_areas_m2,
                                            np.einsum("ij,ij->i", self.face_normals, local))
        # Per-view cosines in a few float32 passes:
        # n·(C − c) = n·C − n·c and |C − c|² = |C|² − 2 C·c + |c|²,
        # with the per-triangle columns stored contiguously (structure of arrays), n outward and positions
        # relative to the bounding-box centre (so float32 keeps its precision wherever the mesh lies).
        self.orientation_sign = float(sign)
        outward = sign * self.face_normals
        self._soa = np.ascontiguousarray(np.concatenate([
            outward.T, local.T, np.einsum("ij,ij->i", outward, local)[None],
            np.einsum("ij,ij->i", local, local)[None]]), dtype=np.float32)
        # For the silhouette ROI (:func:`wbsa.camera.roi.silhouette_pixels`): float32 vertices relative to
        # the centre (3, n) and patches of up to four adjacent faces, as a (k, p) table of their vertices.
        self._local_vertices_f32 = np.ascontiguousarray((vertices - self.center).T, dtype=np.float32)
        self._patches = _patches(np.ascontiguousarray(faces, dtype=np.int64).tobytes(), vertices.shape[0])
        self._o3c = o3d.core
        self._scene = o3d.t.geometry.RaycastingScene()
        self._scene.add_triangles(o3d.core.Tensor(np.ascontiguousarray(vertices, dtype=np.float32)),
                                  o3d.core.Tensor(np.ascontiguousarray(faces, dtype=np.uint32)))

    def __repr__(self) -> str:
        size = self.bbox_max - self.bbox_min
        c = self.center
        return (f"MeshScene({self.n_triangles:,} triangles, area {self.triangle_areas_m2.sum():.4g} m², "
                f"bbox {size[0]:.3g} × {size[1]:.3g} × {size[2]:.3g} m around "
                f"({c[0]:.3g}, {c[1]:.3g}, {c[2]:.3g}) m, {'one-sided' if self.one_sided else 'two-sided'}, "
                f"nthreads {self.nthreads})")

    @property
    def n_triangles(self) -> int:
        """Number of triangles."""
        return int(self.triangle_areas_m2.shape[0])

    def contains(self, point: np.ndarray) -> bool:
        """Whether ``point`` (3,) lies inside the closed surface (ray parity, majority of 3 rays).

        Points outside the bounding box are outside without casting. For open meshes the answer is
        only as good as the parity test (it is used to refuse a camera placed inside the body). A scene
        built with ``surroundings=True`` (a room the camera stands in) contains no point.

        Parameters
        ----------
        point : (3,) float64
            World frame, m.
        """
        if self.surroundings:
            return False
        p = np.asarray(point, dtype=np.float64).reshape(3)
        if np.any(p < self.bbox_min) or np.any(p > self.bbox_max):
            return False
        q = self._o3c.Tensor(p.astype(np.float32).reshape(1, 3))
        return bool(self._scene.compute_occupancy(q, nthreads=self.nthreads, nsamples=3).numpy()[0] > 0.5)

    def cast_rays(self, rays: np.ndarray) -> dict[str, np.ndarray]:
        """Bare Open3D ``cast_rays`` on (n, 6) float32 rays (origin, direction); numpy views of its outputs.

        Parameters
        ----------
        rays : (n, 6) float32
        """
        ans = self._scene.cast_rays(self._o3c.Tensor.from_numpy(rays), nthreads=self.nthreads)
        return {k: v.numpy() for k, v in ans.items()}

    def occluded(self, rays: np.ndarray, t_far: float) -> np.ndarray:
        """(n,) bool: whether anything lies on each ray for 0 < t < ``t_far`` (Open3D ``test_occlusions``).

        Parameters
        ----------
        rays : (n, 6) float32
            Origin and direction.
        t_far : float
            Farthest ray parameter tested.
        """
        ans = self._scene.test_occlusions(self._o3c.Tensor.from_numpy(rays), tnear=0.0, tfar=float(t_far),
                                          nthreads=self.nthreads)
        return ans.numpy().astype(bool)


@lru_cache(maxsize=8)
def _topology(faces_bytes: bytes, n_vertices: int) -> tuple[bool, bool]:
    """(consistently oriented, nearly closed) of a face array (cached: a population shares one topology)."""
    faces = np.frombuffer(faces_bytes, dtype=np.int64).reshape(-1, 3)
    n = np.int64(n_vertices)
    a = faces.reshape(-1)
    b = faces[:, [1, 2, 0]].reshape(-1)
    directed = np.sort(a * n + b)
    if directed.size > 1 and np.any(directed[1:] == directed[:-1]):
        return False, False
    _, counts = np.unique(np.minimum(a, b) * n + np.maximum(a, b), return_counts=True)
    return True, bool(np.count_nonzero(counts == 1) <= 0.01 * counts.size)


@lru_cache(maxsize=8)
def _patches(faces_bytes: bytes, n_vertices: int, levels: int = 2) -> np.ndarray:
    """(k, p) intp vertex table of patches of adjacent faces (read-only, cached per topology).

    Faces sharing an edge are paired, then the pairs are paired (``levels`` = 2), by rounds of matching
    locally lightest edges (seeded random weights); a face or pair left without a partner stays alone.
    Each column lists a patch's distinct vertices, padded with repeats of its first one (at most 6 for two
    pairs of faces). The projected bounding box of a patch holds those of its faces, at half the cost of
    treating the faces one by one on a body mesh.
    """
    faces = np.frombuffer(faces_bytes, dtype=np.int64).reshape(-1, 3)
    m = faces.shape[0]
    # Pairs of faces that share an edge.
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    key = np.minimum(edges[:, 0], edges[:, 1]) * np.int64(n_vertices) + np.maximum(edges[:, 0], edges[:, 1])
    owner = np.tile(np.arange(m), 3)
    order = np.argsort(key, kind="stable")
    key, owner = key[order], owner[order]
    same = np.flatnonzero(key[1:] == key[:-1])
    face_a, face_b = owner[same], owner[same + 1]
    table = np.sort(faces, axis=1)  # (groups, width): distinct vertices of each group, padded by repeats
    group = np.arange(m)            # group of every face
    rng = np.random.default_rng(0)  # fixed: the patches depend only on the topology
    for _ in range(levels):
        a, b = group[face_a], group[face_b]
        keep = a != b
        a, b = a[keep], b[keep]
        n = table.shape[0]
        partner = np.full(n, -1, dtype=np.int64)
        for _round in range(16):
            # Every free group picks its free neighbour over the lightest edge (random weights); an edge
            # picked from both ends is a match (locally lightest edges: most groups match in a few rounds).
            ok = (partner[a] < 0) & (partner[b] < 0)
            if not ok.any():
                break
            ea, eb = a[ok], b[ok]
            weight = rng.random(ea.size)
            lightest = np.full(n, np.inf)
            np.minimum.at(lightest, ea, weight)
            np.minimum.at(lightest, eb, weight)
            chosen = np.flatnonzero((lightest[ea] == weight) & (lightest[eb] == weight))
            ca, cb = ea[chosen], eb[chosen]
            once = np.bincount(np.concatenate([ca, cb]), minlength=n) == 1  # drop the (improbable) ties
            keep = once[ca] & once[cb]
            partner[ca[keep]] = cb[keep]
            partner[cb[keep]] = ca[keep]
        first = np.flatnonzero((partner < 0) | (partner > np.arange(n)))  # singles, and the lower of each pair
        second = np.where(partner[first] < 0, first, partner[first])
        merged = np.sort(np.concatenate([table[first], table[second]], axis=1), axis=1)
        repeat = np.zeros(merged.shape, dtype=bool)
        repeat[:, 1:] = merged[:, 1:] == merged[:, :-1]
        width = int((~repeat).sum(axis=1).max())
        merged[repeat] = np.iinfo(np.int64).max  # repeats to the end, then cut and pad with the first vertex
        merged = np.sort(merged, axis=1)[:, :width]
        pad = merged == np.iinfo(np.int64).max
        merged[pad] = np.broadcast_to(merged[:, :1], merged.shape)[pad]
        new_group = np.empty(n, dtype=np.int64)
        new_group[first] = np.arange(first.size)
        new_group[second] = np.arange(first.size)
        group = new_group[group]
        table = merged
    out = np.ascontiguousarray(table.T, dtype=np.intp)
    out.setflags(write=False)
    return out


@lru_cache(maxsize=8)
def boundary_loops(faces_bytes: bytes, n_vertices: int) -> list[np.ndarray]:
    """Vertex sets of the connected groups of boundary edges (edges of one face) of a mesh (cached per topology).

    Each group is a hole; its cap (a fan from the mean of its vertices) closes it.

    Parameters
    ----------
    faces_bytes : bytes
        The faces' (m, 3) int64 array as bytes (the cache key).
    n_vertices : int
    """
    faces = np.frombuffer(faces_bytes, dtype=np.int64).reshape(-1, 3)
    a = faces.reshape(-1)
    b = faces[:, [1, 2, 0]].reshape(-1)
    key = np.minimum(a, b) * n_vertices + np.maximum(a, b)
    uniq, counts = np.unique(key, return_counts=True)
    edges = uniq[counts == 1]
    if edges.size == 0:
        return []
    u, v = np.divmod(edges, n_vertices)
    # connected components of the boundary edges (union-find by repeated label propagation)
    verts = np.unique(np.concatenate([u, v]))
    label = {int(x): int(x) for x in verts}

    def find(x: int) -> int:
        while label[x] != x:
            label[x] = label[label[x]]
            x = label[x]
        return x

    for x, y in zip(u.tolist(), v.tolist()):
        rx, ry = find(x), find(y)
        if rx != ry:
            label[max(rx, ry)] = min(rx, ry)
    roots = np.array([find(int(x)) for x in verts])
    return [verts[roots == r].astype(np.int32) for r in np.unique(roots)]


def _orientation(faces: np.ndarray, n_vertices: int, areas: np.ndarray,
                 normal_dot_centroid: np.ndarray) -> tuple[bool, float]:
    """Whether the mesh is a consistently oriented, (nearly) closed surface, and the sign that turns its normals out.

    Consistent: no directed edge is used twice. Nearly closed: at most 1 % of the edges border a single face
    (a body's small eye and mouth openings). Outward: positive enclosed volume, ⅓ Σ area · n·c (divergence
    theorem, c the centroids relative to any point). Returns ``(one_sided, sign)``; ``one_sided`` False means
    back faces must be treated like front faces.
    """
    consistent, closed = _topology(np.ascontiguousarray(faces, dtype=np.int64).tobytes(), int(n_vertices))
    if not (consistent and closed):
        return False, 1.0
    volume = float(np.einsum("i,i->", areas, normal_dot_centroid)) / 3.0
    if abs(volume) < 1e-12:
        return False, 1.0
    return True, 1.0 if volume > 0 else -1.0


def validate_mesh(mesh: TriangleMesh) -> tuple[np.ndarray, np.ndarray]:
    """Check a mesh for ray casting; returns (vertices (n, 3) float64, faces (m, 3) int64).

    Parameters
    ----------
    mesh : TriangleMesh

    Raises
    ------
    WbsaError
        If it is not a TriangleMesh, has no triangles, non-finite vertices or out-of-range indices.
    """
    if not isinstance(mesh, TriangleMesh):
        raise WbsaError(f"expected a TriangleMesh, got {type(mesh).__name__}")
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or vertices.shape[0] == 0:
        raise WbsaError(f"the mesh has no vertices (shape {vertices.shape}); check the mesh file")
    if faces.ndim != 2 or faces.shape[1] != 3 or faces.shape[0] == 0:
        raise WbsaError("the mesh has no triangles (a point cloud or an empty file?); give a triangle mesh")
    if not np.issubdtype(faces.dtype, np.integer):
        raise WbsaError(f"mesh faces must be integer vertex indices, got {faces.dtype}")
    if not np.all(np.isfinite(vertices)):
        raise WbsaError("the mesh has non-finite vertex coordinates (NaN or inf); repair the mesh")
    if faces.min() < 0 or faces.max() >= vertices.shape[0]:
        raise WbsaError(f"mesh faces index vertices outside 0..{vertices.shape[0] - 1}; the mesh file is corrupt")
    return vertices, faces.astype(np.int64, copy=False)
