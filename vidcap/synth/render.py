"""Drawing the cylinder body: depth-buffered, shaded cylinders with rounded inner
joints (:func:`render_body`), slow lighting drift (:func:`lighting_gains`) and pixel
noise (:func:`finish_frame`)."""

from __future__ import annotations

from types import MappingProxyType

import numpy as np

from vidcap.body import (
    SEGMENT_JOINTS,
    SEGMENT_NAMES,
    BodyModel,
)
from vidcap.synth._geometry import unit
from vidcap.synth.camera import (
    OrthoCamera,
)

#: Clothing colours (BGR): a red shirt, dark blue trousers, skin, dark grey shoes.
SHIRT = (40, 45, 190)
TROUSERS = (95, 45, 25)
SKIN = (120, 160, 215)
SHOES = (55, 55, 60)
#: A foot (drawn only for a body with feet, ``foot > 0``): a capsule whose radius is half
#: the ankle's height above the soles, from below the ankle forward to the toes, its
#: centre line ``FOOT_REACH`` x the stature long. With the capsule's rounded ends the
#: foot is 0.145 of the stature from heel to toe (Drillis & Contini's foot length
#: 0.152 H, Winter Fig. 4.1); the ankle sits a quarter of it from the heel.
FOOT_REACH = 0.106
_SEGMENT_COLOUR = {
    "torso": SHIRT, "head": SKIN,
    "l_upper_arm": SHIRT, "r_upper_arm": SHIRT, "l_lower_arm": SKIN, "r_lower_arm": SKIN,
    "l_upper_leg": TROUSERS, "r_upper_leg": TROUSERS,
    "l_lower_leg": TROUSERS, "r_lower_leg": TROUSERS,
}
#: Which ends of each cylinder are rounded by a sphere of the segment's radius (the
#: joints inside a limb: shoulders, elbows, hips, knees). The other ends are the flat
#: discs of a cylinder (their projections are ellipses): torso, head, hands, feet end
#: at the joint as the seed's cylinder model does.
_ROUND_ENDS = MappingProxyType(
    {
        "torso": (False, False), "head": (False, False),
        "l_upper_arm": (True, True), "r_upper_arm": (True, True),
        "l_lower_arm": (True, False), "r_lower_arm": (True, False),
        "l_upper_leg": (True, True), "r_upper_leg": (True, True),
        "l_lower_leg": (True, False), "r_lower_leg": (True, False),
    }
)
#: Direction toward the light in camera coordinates (right, down, view): upper left,
#: in front.
_LIGHT = unit(np.array([-0.45, -0.6, -0.65]))


def _draw_segment(img, zbuf, a, b, za, zb, r, axis_v, colour, round_ends):
    """Z-buffer one shaded cylinder, a -> b in image pixels, into ``img`` (float32).

    ``za``, ``zb`` are the end depths and ``r`` the radius, all in pixels; ``axis_v``
    is the cosine between the 3D axis and the view direction (foreshortening of the
    flat end discs); ``round_ends`` says which ends are spheres instead of discs.
    The body is exact for an orthographic view (a band of half-width r); the depth
    and normals are those of a cylinder lying in the image plane, close enough to
    order overlapping segments and to shade them.
    """
    H, W = zbuf.shape
    lo = np.floor(np.minimum(a, b) - r - 1).astype(int)
    hi = np.ceil(np.maximum(a, b) + r + 1).astype(int)
    x0, y0 = max(lo[0], 0), max(lo[1], 0)
    x1, y1 = min(hi[0], W), min(hi[1], H)
    if x1 <= x0 or y1 <= y0:
        return
    px = np.arange(x0, x1, dtype=np.float32)[None, :] - a[0]
    py = np.arange(y0, y1, dtype=np.float32)[:, None] - a[1]
    ab = (b - a).astype(np.float32)
    L = float(np.hypot(ab[0], ab[1]))
    ux, uy = (float(ab[0]) / L, float(ab[1]) / L) if L > 1e-6 else (1.0, 0.0)
    r2 = r * r
    par = px * ux + py * uy  # along the axis from a, px
    perp = px * uy - py * ux  # signed, across the axis
    perp2 = perp * perp
    h_cyl = np.sqrt(np.clip(1.0 - perp2 / r2, 0.0, 1.0))
    # light on a cylinder: normal across the axis in the image, bulging toward us
    lam_cyl = (perp / r) * (uy * _LIGHT[0] - ux * _LIGHT[1]) - h_cyl * _LIGHT[2]
    inf = np.float32(np.inf)
    inside = (par >= 0) & (par <= L) & (perp2 < r2)
    t = np.clip(par / L, 0.0, 1.0) if L > 1e-6 else np.zeros_like(par)
    depth = np.where(inside, za + t * (zb - za) - h_cyl * r, inf)
    lam = lam_cyl
    cos_a = max(abs(float(axis_v)), 1e-3)
    for end_par, z_end, rounded in ((0.0, za, round_ends[0]), (L, zb, round_ends[1])):
        dpar = par - end_par
        if rounded:  # sphere
            d2 = dpar * dpar + perp2
            cap = d2 < r2
            h = np.sqrt(np.clip(1.0 - d2 / r2, 0.0, 1.0))
            dz = z_end - h * r
            nx = (dpar * ux + perp * uy) / r
            ny = (dpar * uy - perp * ux) / r
            lam_cap = nx * _LIGHT[0] + ny * _LIGHT[1] - h * _LIGHT[2]
        else:  # flat disc seen obliquely: an ellipse, shaded as a face toward us
            cap = (dpar / (r * cos_a)) ** 2 + perp2 / r2 < 1.0
            dz = np.full_like(par, z_end - 0.5 * r * cos_a)
            lam_cap = np.full_like(par, 0.55)
        closer = cap & (dz < depth)
        depth = np.where(closer, dz, depth)
        lam = np.where(closer, lam_cap, lam)
    sub_z = zbuf[y0:y1, x0:x1]
    upd = depth < sub_z
    if not upd.any():
        return
    shade = 0.45 + 0.6 * np.clip(lam, 0.0, 1.0)
    sub_img = img[y0:y1, x0:x1]
    sub_img[upd] = shade[upd][:, None] * np.asarray(colour, np.float32)
    sub_z[upd] = depth[upd]


def render_body(
    joints3d: np.ndarray,
    camera: OrthoCamera,
    body: BodyModel,
    background: np.ndarray,
    *,
    colours: dict | None = None,
    foot: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Draw the posed cylinder body over a background, nearest surface on top.

    Parameters
    ----------
    joints3d : numpy.ndarray, shape (15, 3)
        One frame's joints, metres.
    camera : OrthoCamera
    body : BodyModel
        Radii of the segments.
    background : numpy.ndarray, shape (H, W, 3) uint8
    colours : dict, optional
        BGR colour per segment name (default: shirt, trousers, skin).
    foot : float
        The share of the standing height (head top to soles) below the ankles: a foot is
        drawn under each ankle (:func:`foot_segments`; 0, the default: none, the seed's
        body, whose ankles are on the floor). ``body.height`` is head top to ankles.

    Returns
    -------
    image : numpy.ndarray, shape (H, W, 3) float32
        BGR, 0..255, before noise and lighting.
    mask : numpy.ndarray, shape (H, W) bool
        Pixels covered by the body.
    """
    colours = colours or _SEGMENT_COLOUR
    H, W = background.shape[:2]
    img = background.astype(np.float32)
    zbuf = np.full((H, W), np.inf, np.float32)
    uv = camera.project(joints3d).astype(np.float32)
    z = camera.depth(joints3d)
    s = camera.pixels_per_metre
    for k, name in enumerate(SEGMENT_NAMES):
        p, d = SEGMENT_JOINTS[k]
        bone = joints3d[d] - joints3d[p]
        n = np.linalg.norm(bone)
        axis_v = (bone @ camera.view_dir) / n if n > 1e-9 else 1.0
        # depths in pixels so they compare with the radius in pixels
        _draw_segment(
            img, zbuf, uv[p], uv[d], np.float32(z[p] * s), np.float32(z[d] * s),
            np.float32(body.radius(name) * s), axis_v, colours[name], _ROUND_ENDS[name],
        )
    if foot > 0:
        heels, toes, radius = foot_segments(joints3d, body.height / (1.0 - foot), foot)
        zh, zt = camera.depth(heels) * s, camera.depth(toes) * s
        uh, ut = camera.project(heels).astype(np.float32), camera.project(toes).astype(np.float32)
        for k in range(2):
            bone = toes[k] - heels[k]
            axis_v = (bone @ camera.view_dir) / max(np.linalg.norm(bone), 1e-9)
            _draw_segment(img, zbuf, uh[k], ut[k], np.float32(zh[k]), np.float32(zt[k]),
                          np.float32(radius * s), axis_v, SHOES, (True, True))
    return img, np.isfinite(zbuf)


def foot_segments(joints3d: np.ndarray, stature: float, foot: float):
    """The two feet of a posed body as capsules: heel and toe centres and the radius.

    Each foot hangs from its ankle: its sole is ``foot * stature`` below the ankle
    along the shin (a foot held at a right angle to the shin), and it points along
    the body's forward direction (from the hips and shoulders) made square to the
    shin.

    Parameters
    ----------
    joints3d : numpy.ndarray, shape (15, 3)
        One frame's joints, metres, Y up.
    stature : float
        Head top to soles, metres.
    foot : float
        Share of the stature below the ankles (> 0).

    Returns
    -------
    heels, toes : numpy.ndarray, shape (2, 3)
        Capsule end centres (left, right), metres.
    radius : float
        Metres.
    """
    from vidcap.body import JOINT_INDEX
    from vidcap.synth.camera import body_forward

    radius = 0.5 * foot * stature
    fwd = body_forward(joints3d[None])[0]
    heels, toes = np.empty((2, 3)), np.empty((2, 3))
    for k, side in enumerate("lr"):
        knee, ankle = joints3d[JOINT_INDEX[f"{side}_knee"]], joints3d[JOINT_INDEX[f"{side}_ankle"]]
        down = unit(ankle - knee)
        ahead = fwd - (fwd @ down) * down
        ahead = unit(ahead) if np.linalg.norm(ahead) > 1e-6 else fwd
        heels[k] = ankle + radius * down - 0.25 * FOOT_REACH * stature * ahead
        toes[k] = heels[k] + FOOT_REACH * stature * ahead
    return heels, toes, float(radius)


def lighting_gains(
    n_frames: int, fps: float, amount: float, rng: np.random.Generator
) -> np.ndarray:
    """Slow global brightness/colour gains (F, 3) around 1 (``amount`` = relative swing).

    One smooth cycle over max(4 s, the clip) with a random phase, plus a smaller
    per-channel tint drift.
    """
    t = np.arange(n_frames) / fps
    period = max(4.0, n_frames / fps)
    ph = rng.uniform(0, 2 * np.pi, 4)
    base = np.sin(2 * np.pi * t / period + ph[0])
    tint = 0.3 * np.sin(2 * np.pi * t[:, None] / period + ph[1:][None, :])
    return 1.0 + amount * (base[:, None] + tint)


def finish_frame(
    image: np.ndarray, rng: np.random.Generator, *, noise: float = 0.0, gain=None
) -> np.ndarray:
    """Apply lighting gain (3,) and Gaussian noise (sigma, grey levels); return uint8."""
    out = image if gain is None else image * np.asarray(gain, np.float32)
    if noise > 0:
        out = out + np.float32(noise) * rng.standard_normal(out.shape, dtype=np.float32)
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)
