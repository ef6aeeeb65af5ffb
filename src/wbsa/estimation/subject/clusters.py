"""3-D clusters of a depth image: low returns attached to the objects they touch, occluding parts merged."""

from __future__ import annotations

import numpy as np

from wbsa.estimation.subject.cloud import Plane

#: Parts that touch in the image are merged when a fifth of their contact has a depth step under this (m)
MERGE_DEPTH_GAP_M = 0.8
#: ... and they share at least this many neighbouring pixel pairs.
MERGE_MIN_CONTACTS = 5
#: A person's legs and hips (10–40 % of its height) span at most this horizontally (m); two people more.
MAX_FOOTPRINT_M = 0.9
#: Only a union reaching this close to the floor (m) has legs and hips to measure: an upper body with its
#: arm, both clear of the floor, would measure its chest and elbows instead ...
STANDING_M = 0.3
#: ... so such a union is spared the footprint test when its smaller part is arm-sized (bounding-box
#: diagonal at most this, m); two upper bodies are still held to it.
ARM_MAX_M = 0.9
#: Seen from the side, the far arm of a body with its arms out is seen past the near arm and torso, up to a
#: metre behind them. An arm-sized part clear of the floor and below the union's shoulders, lying behind
#: what it touches, may step this far (m) ...
FAR_ARM_GAP_M = 1.2
#: ... when it is a surface, not a seam: at least this many of its pixels have all 4 neighbours in it
#: (mixed-pixel returns left between a body and the wall lie in strips a pixel or two wide).
FAR_ARM_INTERIOR = 5
#: Highest a far arm's top reaches, as a share of the union's height over the floor (shoulders; a head
#: behind the subject, another person's, stays out).
FAR_ARM_TOP = 0.85
#: Farthest a far arm reaches from the body's vertical axis (the median of what it joins), as a share of
#: the union's height: arm span is about stature, so a hand reaches half of it (an unfound wall does not).
FAR_ARM_REACH = 0.55
#: A part more than this (m) behind what it touches, and seen through a loop of it, is not the body's far
#: side (a heavy trunk and an arm are thinner) but the room (the wall seen inside an arm on the hip).
LOOP_GAP_M = 0.65


def footprint_m(points: np.ndarray, up: np.ndarray, heights_m: np.ndarray | None = None) -> float:
    """Horizontal extent (m, bounding-box diagonal) of the points between 10 % and 40 % of the object's height.

    Parameters
    ----------
    points : (k, 3) float64
        The object's points (camera frame, m).
    up : (3,) float64
        Unit up direction (the floor's normal).
    heights_m : (k,) float64, optional
        The points' heights over the floor, where one is seen: the band is then 10–40 % of the top's height
        over the floor, where the hips are even when the frame cuts the legs off (from the object's lowest
        point, a body cut at the knees would be measured at its hands).
    """
    along = points @ up if heights_m is None else np.asarray(heights_m, dtype=np.float64)
    top = np.quantile(along, 0.998)
    lo = np.quantile(along, 0.002) if heights_m is None else 0.0
    band = points[(along >= lo + 0.1 * (top - lo)) & (along <= lo + 0.4 * (top - lo))]
    if len(band) < 3:
        return 0.0
    flat = band - np.outer(band @ up, up)
    e1 = np.array([1.0, 0.0, 0.0]) - up[0] * up
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(up, e1)
    q = np.stack([flat @ e1, flat @ e2], axis=1)
    ext = np.quantile(q, 0.99, axis=0) - np.quantile(q, 0.01, axis=0)
    return float(np.hypot(*ext))


def attach_low(low: np.ndarray, tree, labels: np.ndarray, gap: float) -> np.ndarray:
    """Label of the object each low voxel's group touches (−1: none).

    Low voxels are grouped among themselves (closer than ``gap``); a group joins the object that most of
    its members touching an object touch.

    Parameters
    ----------
    low : (k, 3) float64
        The low voxels' centres (camera frame, m).
    tree : scipy.spatial.cKDTree
        Of the objects' voxels.
    labels : (v,) int
        Object label of each voxel of ``tree``.
    gap : float
        Largest gap (m) within a group and to an object.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    pairs = cKDTree(low).query_pairs(gap, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(low), len(low)))
    _, group = connected_components(graph, directed=False)
    dist, near = tree.query(low, distance_upper_bound=gap)
    touch = np.isfinite(dist)
    out = np.full(len(low), -1)
    if not touch.any():
        return out
    pairs_gl = np.stack([group[touch], labels[near[touch]]], axis=1)
    uniq, counts = np.unique(pairs_gl, axis=0, return_counts=True)
    order = np.lexsort((-counts, uniq[:, 0]))  # per group, the most touched object first
    uniq = uniq[order]
    first = np.r_[True, uniq[1:, 0] != uniq[:-1, 0]]
    best = dict(zip(uniq[first, 0].tolist(), uniq[first, 1].tolist()))
    return np.array([best.get(g, -1) for g in group.tolist()])


def merge_occluding(pixel_label: np.ndarray, pix: np.ndarray, points: np.ndarray, shape: tuple[int, int],
                    floor: Plane | None, max_height_m: float, max_width_m: float) -> np.ndarray:
    """Merge clusters that touch in the image across a small depth step, while the union stays person-sized.

    Clusters touch where their pixels are side by side, or one pixel apart with no return between them: a
    camera with a flying-pixel filter drops the pixels straddling a depth edge, and a side view seen so fell
    apart at the waist, hidden by the near arm (13 of 300 bench images with every such pixel dropped).

    Seen from the side, a body's far leg and arm are hidden where they join it, so they form clusters of
    their own; they touch the near side in the image with a depth step of a body's width (or of an arm
    reaching towards the camera, which can hide the waist). Pairs are merged by decreasing contact length
    when a fifth of the contact steps less than 0.8 m in depth and the union is person-sized: not too tall
    or wide, and its legs and hips span at most 0.9 m (two people more). The last test is skipped for an
    upper body and an arm-sized part (:data:`ARM_MAX_M`) clear of the floor (the union stays over
    :data:`STANDING_M` above it; there is no such union without a floor): their "hips" are the elbows.
    A far arm (:data:`FAR_ARM_GAP_M`) may step farther: an arm-sized part, smaller than what it joins, at
    least :data:`STANDING_M` above the floor, below :data:`FAR_ARM_TOP` of the union's height, within :data:`FAR_ARM_REACH` of it
    from the body's axis, behind what it touches, with an interior (:data:`FAR_ARM_INTERIOR`). A smaller
    part more than :data:`LOOP_GAP_M` behind and seen through a loop of the larger (the wall inside an arm
    on the hip) is never merged.

    Parameters
    ----------
    pixel_label : (k,) int
        Cluster of each return (−1: none); ``pix`` (k,) its flat pixel index, ``points`` (k, 3) its point.
    shape : (int, int)
        Image size (h, w).
    floor : Plane or None
        The floor (its normal is the vertical); None: the image's up (−y), and every union is held to the
        footprint.
    max_height_m, max_width_m : float
        Largest person.

    Returns
    -------
    (k,) int
        Labels after merging (merged clusters take the label of the larger part).
    """
    h, w = shape
    up = floor.normal if floor is not None else np.array([0.0, -1.0, 0.0])
    floor_up_m = floor.offset if floor is not None else np.inf  # along up; without a floor, nothing is clear
    img = np.full(h * w, -1, dtype=np.int64)
    img[pix] = pixel_label
    rng = np.zeros(h * w)
    rng[pix] = np.linalg.norm(points, axis=1)
    img, rng = img.reshape(h, w), rng.reshape(h, w)
    la, lb, step = [], [], []
    touching = ((img[:, :-1], img[:, 1:], rng[:, :-1], rng[:, 1:], True), (img[:-1], img[1:], rng[:-1], rng[1:], True),
                # across one pixel without a return: cameras that drop the pixels straddling a depth edge
                (img[:, :-2], img[:, 2:], rng[:, :-2], rng[:, 2:], rng[:, 1:-1] == 0),
                (img[:-2], img[2:], rng[:-2], rng[2:], rng[1:-1] == 0))
    for a, b, ra, rb, between in touching:
        sel = (a >= 0) & (b >= 0) & (a != b) & between
        la.append(np.minimum(a[sel], b[sel]))
        lb.append(np.maximum(a[sel], b[sel]))
        step.append(np.where(a[sel] < b[sel], rb[sel] - ra[sel], ra[sel] - rb[sel]))  # range of lb's side − la's
    la, lb, step = np.concatenate(la), np.concatenate(lb), np.concatenate(step)
    if la.size == 0:
        return pixel_label
    pairs, inverse, counts = np.unique(np.stack([la, lb], 1), axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    order = np.argsort(inverse, kind="stable")
    splits = np.split(step[order], np.cumsum(counts)[:-1])
    near_gap = np.array([np.quantile(np.abs(g), 0.2) for g in splits])
    behind_b = np.array([np.median(g) > 0 for g in splits])  # the larger label lies behind the smaller
    # extents of every cluster along up and two horizontal axes
    e1 = np.array([1.0, 0.0, 0.0]) - up[0] * up
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(up, e1)
    proj = points @ np.stack([up, e1, e2], axis=1)
    labels = np.unique(pixel_label[pixel_label >= 0])
    lo = {int(c): proj[pixel_label == c].min(axis=0) for c in labels}
    hi = {int(c): proj[pixel_label == c].max(axis=0) for c in labels}
    members = {int(c): [np.flatnonzero(pixel_label == c)] for c in labels}
    size = {c: len(m[0]) for c, m in members.items()}
    parent = {int(c): int(c) for c in labels}

    def root(c: int) -> int:
        while parent[c] != c:
            parent[c] = parent[parent[c]]
            c = parent[c]
        return c

    pix_row, pix_col = np.divmod(pix, w)

    def image_masks(parts: list[int], pad: int) -> list[np.ndarray]:
        """Image masks of ``parts`` over their joint bounding box widened by ``pad`` pixels (within the
        image): the morphology below then costs what the parts cover, not the whole image, and gives the
        same pixels as on the whole image (the box keeps a ring of ``pad`` background pixels)."""
        rows = [pix_row[np.concatenate(members[c])] for c in parts]
        cols = [pix_col[np.concatenate(members[c])] for c in parts]
        r0 = max(min(r.min() for r in rows) - pad, 0)
        c0 = max(min(c.min() for c in cols) - pad, 0)
        r1 = min(max(r.max() for r in rows) + pad + 1, h)
        c1 = min(max(c.max() for c in cols) + pad + 1, w)
        out = []
        for r, c in zip(rows, cols):
            m = np.zeros((r1 - r0, c1 - c0), dtype=bool)
            m[r - r0, c - c0] = True
            out.append(m)
        return out

    def through_loop(back: int, front: int) -> bool:
        """Whether most of part ``back`` is seen through a loop of ``front`` (the wall inside an arm on
        the hip)."""
        from scipy import ndimage

        part, front_mask = image_masks([back, front], pad=3)  # closing by 2: a ring of 3 stays background
        body = ndimage.binary_closing(front_mask, iterations=2)
        return np.count_nonzero(part & ndimage.binary_fill_holes(body)) > np.count_nonzero(part) // 2

    def far_arm(back: int, front: int, new_lo: np.ndarray, new_hi: np.ndarray) -> bool:
        """Whether part ``back``, behind ``front``, is a far arm of their union (see the doc above)."""
        from scipy import ndimage

        back_top, top = hi[back][0] - floor_up_m, new_hi[0] - floor_up_m
        if not (lo[back][0] - floor_up_m >= STANDING_M and back_top <= FAR_ARM_TOP * top
                and np.linalg.norm(hi[back] - lo[back]) <= ARM_MAX_M and size[back] < size[front]):
            return False
        axis = np.median(proj[np.concatenate(members[front]), 1:], axis=0)
        reach = np.linalg.norm(proj[np.concatenate(members[back]), 1:] - axis, axis=1)
        if np.quantile(reach, 0.95) > FAR_ARM_REACH * top:
            return False
        return np.count_nonzero(ndimage.binary_erosion(image_masks([back], pad=1)[0])) >= FAR_ARM_INTERIOR  # 4-nbr

    for i in np.argsort(-counts, kind="stable"):
        if counts[i] < MERGE_MIN_CONTACTS or near_gap[i] > FAR_ARM_GAP_M:
            continue
        a, b = root(int(pairs[i, 0])), root(int(pairs[i, 1]))
        if a == b:
            continue
        new_lo, new_hi = np.minimum(lo[a], lo[b]), np.maximum(hi[a], hi[b])
        ext = new_hi - new_lo
        if ext[0] > max_height_m or np.hypot(ext[1], ext[2]) > max_width_m:
            continue
        back, front = (b, a) if behind_b[i] else (a, b)
        if near_gap[i] > MERGE_DEPTH_GAP_M and not far_arm(back, front, new_lo, new_hi):
            continue
        if near_gap[i] > LOOP_GAP_M and size[back] < size[front] and through_loop(back, front):
            continue
        union = np.concatenate(members[a] + members[b])
        part = a if size[a] < size[b] else b
        arm_clear = new_lo[0] - floor_up_m >= STANDING_M and np.linalg.norm(hi[part] - lo[part]) <= ARM_MAX_M
        if not arm_clear and footprint_m(points[union], up) > MAX_FOOTPRINT_M:
            continue
        keep, gone = (a, b) if size[a] >= size[b] else (b, a)
        parent[gone] = keep
        lo[keep], hi[keep], size[keep] = new_lo, new_hi, size[a] + size[b]
        members[keep] = [union]
    lut = {c: root(c) for c in parent}
    out = pixel_label.copy()
    ok = out >= 0
    out[ok] = np.array([lut[int(c)] for c in out[ok]])
    return out


#: Cell of the height map over the floor that people standing in one object are told apart on (m).
HEIGHT_CELL_M = 0.05
#: Two tops of an object are two people's heads when each stands this far (m) above the highest pass
#: between them: a head is 0.2–0.25 m tall over the shoulders; the tops of one head lie within noise.
HEAD_PROMINENCE_M = 0.15
#: Tops closer than this (m, across the floor) are one head.
HEAD_RADIUS_M = 0.15


def split_people(points: np.ndarray, floor: Plane, min_top_m: float) -> np.ndarray:
    """People standing side by side or close, touching in 3-D, told apart by their heads.

    Seen from above (the floor's normal), every cell of :data:`HEIGHT_CELL_M` holds the height of the
    highest return over it. Its local tops (within :data:`HEAD_RADIUS_M`) at least ``min_top_m`` over the
    floor flood the map downhill (a watershed: every cell joins the top it is reached from over the
    highest passes); two tops whose floods meet at a pass less than :data:`HEAD_PROMINENCE_M` below the
    lower of them are one (a head's tops, a shoulder). What touches between two people (an arm, a
    shoulder) lies below both heads, so the floods meet there.

    Parameters
    ----------
    points : (k, 3) float64
        Camera-frame points of one object (m).
    floor : Plane
    min_top_m : float
        Lowest head over the floor (m).

    Returns
    -------
    (k,) int
        The person of every point, 0 to n − 1 (all 0 when the object has one head).
    """
    from scipy import ndimage

    up = floor.normal
    height = floor.height(points)
    e1 = np.array([1.0, 0.0, 0.0]) - up[0] * up
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(up, e1)
    cell = np.floor(np.stack([points @ e1, points @ e2], axis=1) / HEIGHT_CELL_M).astype(np.int64)
    cell -= cell.min(axis=0)
    shape = tuple(cell.max(axis=0) + 1)
    top = np.full(shape, -np.inf)
    np.maximum.at(top, (cell[:, 0], cell[:, 1]), height)
    seen = np.isfinite(top)
    radius = max(int(round(HEAD_RADIUS_M / HEIGHT_CELL_M)), 1)
    peaks = seen & (top >= ndimage.maximum_filter(np.where(seen, top, -np.inf), size=2 * radius + 1))
    peaks &= top >= min_top_m
    markers, n = ndimage.label(peaks, structure=np.ones((3, 3), dtype=int))
    out = np.zeros(len(points), dtype=np.int64)
    if n < 2:
        return out
    # flood downhill: the cost of a cell is its depth below the highest top, in millimetres
    cost = np.where(seen, np.round(1000.0 * (np.max(top[seen]) - np.where(seen, top, 0.0))), 65535)
    region = ndimage.watershed_ift(np.clip(cost, 0, 65535).astype(np.uint16), markers,
                                   structure=np.ones((3, 3), dtype=int))
    peak_m = np.array([np.max(top[markers == i]) for i in range(1, n + 1)])
    # the highest pass between every two touching regions (over seen cells)
    parent = list(range(n))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    passes: dict[tuple[int, int], float] = {}
    rows, cols = shape
    for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):  # every pair of neighbouring cells once
        here = (slice(0, rows - dr), slice(max(0, -dc), cols - max(0, dc)))
        there = (slice(dr, rows), slice(max(0, dc), cols - max(0, -dc)))
        a, b, ta, tb = region[here], region[there], top[here], top[there]
        sel = (a != b) & np.isfinite(ta) & np.isfinite(tb)
        for i, j, h in zip(a[sel].tolist(), b[sel].tolist(), np.minimum(ta[sel], tb[sel]).tolist()):
            key = (min(i, j) - 1, max(i, j) - 1)
            passes[key] = max(passes.get(key, -np.inf), h)
    for (i, j), h in sorted(passes.items(), key=lambda kv: -kv[1]):
        ri, rj = root(i), root(j)
        if ri != rj and h > min(peak_m[ri], peak_m[rj]) - HEAD_PROMINENCE_M:
            keep, gone = (ri, rj) if peak_m[ri] >= peak_m[rj] else (rj, ri)
            parent[gone] = keep
    person = np.array([root(i) for i in range(n)])
    heads = np.unique(person)
    if len(heads) < 2:
        return np.zeros(len(points), dtype=np.int64)
    # every return belongs to the nearest head's vertical axis: the middle of the returns within
    # HEAD_PROMINENCE_M of that head's top (above every pass to the others), across the floor
    flat = np.stack([points @ e1, points @ e2], axis=1)
    region_of = person[region[cell[:, 0], cell[:, 1]] - 1]
    axes = np.array([np.median(flat[(region_of == k) & (height > peak_m[k] - HEAD_PROMINENCE_M)], axis=0)
                     for k in heads])
    return np.argmin(((flat[:, None, :] - axes[None]) ** 2).sum(axis=2), axis=1)
