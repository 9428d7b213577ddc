"""Does the cues' colour model find the forearms and hands on real footage? (issue 27)

For every real clip's scored range (``real_clips.py``; the tuning clips of
``pose2d_real_pipeline.TUNING`` unless ``--all``) with MediaPipe's person masks: the clip's
:class:`vidcap.video.fit.cues.ColourModel` learned as ``fit_sequence(cues='all')`` learns
it (:func:`vidcap.video.fit.tracking.sequence_colours`, the ``human`` body), then every
third frame's skin likelihood map (:func:`vidcap.video.fit.cues.cue_maps`, on the fit's
normalised grid) read at MediaPipe's landmarks: its hand points (pinky, index, thumb),
the forearms (elbow to wrist), the upper arms, the torso (its centre and half way up to
the shoulders), the thighs and shins, and the silhouette's border (the pixels an erosion
by one removes). Printed per clip: the mean likelihood at each, the AUC of hands and
forearms against the torso (0.5: the colour tells an arm on the torso nothing), and the
share of torso samples at or above :data:`vidcap.video.fit.cues.SKIN_MIN` (where the cue
search's skin gate lets an arm move onto the torso). MediaPipe's landmarks are a
reference, not the truth.

Usage: ``VIDCAP_DATA=/work/data PYTHONPATH=. python benchmarks/cues_real_colours.py
[--all] [--only NAME]``
"""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from pose2d_real_pipeline import TUNING  # noqa: E402
from real_clips import real_clips, stretch  # noqa: E402

PARTS = ("hand", "forearm", "upperarm", "torso", "thigh", "shin", "border")


def auc(pos, neg) -> float:
    """P(a positive sample scores above a negative one), ties counted half."""
    pos, neg = np.asarray(pos, float), np.asarray(neg, float)
    if not len(pos) or not len(neg):
        return float("nan")
    both = np.concatenate([pos, neg])
    order = both.argsort(kind="stable")
    ranks = np.empty(len(both))
    ranks[order] = np.arange(len(both))
    for v in np.unique(both):  # ties: mean rank
        same = both == v
        ranks[same] = ranks[same].mean()
    return float((ranks[:len(pos)].sum() - len(pos) * (len(pos) - 1) / 2)
                 / (len(pos) * len(neg)))


def clip_samples(clip, step: int = 3) -> dict:
    """Skin likelihood samples per part of :data:`PARTS` over ``clip``'s range."""
    from vidcap.io.video import iter_frames
    from vidcap.video.fit.cueframes import FrameCrops
    from vidcap.video.fit.cues import cue_maps
    from vidcap.video.fit.normalise import normalise_mask
    from vidcap.video.fit.options import FitOptions
    from vidcap.video.fit.proportions import fit_keywords, human_proportions
    from vidcap.video.fit.tracking import sequence_colours

    with np.load(clip.reference) as d:
        masks = stretch(d["masks"], clip).astype(bool)
        marks = stretch(d["landmarks"], clip)
        names = [str(n) for n in d["names"]]
    kw = fit_keywords(human_proportions().factors)
    options = FitOptions.from_keywords(dict(kw))
    crops = FrameCrops.from_frames(
        iter_frames(clip.video, start=clip.start, stop=clip.start + len(masks)), masks)
    model = sequence_colours(masks, crops, cues="all", **kw)
    out = {p: [] for p in PARTS}
    hands = [i for i, n in enumerate(names) if any(t in n for t in ("pinky", "index", "thumb"))]
    at = {n: names.index(n) for n in names}
    for k in range(0, len(masks), step):
        mk = marks[k]
        if not masks[k].any() or not np.isfinite(mk).all():
            continue
        norm = normalise_mask(masks[k], height=options.height, body_height=options.body_height)
        skin = cue_maps(crops.cue_image(k, norm), norm.mask, model).stack[..., 0]
        h, w = skin.shape

        def read(points, part, skin=skin, norm=norm, h=h, w=w):
            for x, y in np.asarray(norm.to_normalised(np.atleast_2d(points))):
                i, j = int(round(y)), int(round(x))
                if 0 <= i < h and 0 <= j < w and norm.mask[i, j]:
                    out[part].append(float(skin[i, j]))

        for s in ("left", "right"):
            sh, el, wr = (mk[at[f"{s}_{j}"]] for j in ("shoulder", "elbow", "wrist"))
            hp, kn, an = (mk[at[f"{s}_{j}"]] for j in ("hip", "knee", "ankle"))
            read(mk[[i for i in hands if names[i].startswith(s)]], "hand")
            read([el + t * (wr - el) for t in (0.5, 0.75, 1.0)], "forearm")
            read([sh + t * (el - sh) for t in (0.3, 0.5, 0.7)], "upperarm")
            read([hp + t * (kn - hp) for t in (0.3, 0.5, 0.7)], "thigh")
            read([kn + t * (an - kn) for t in (0.3, 0.5, 0.7)], "shin")
        shoulders = (mk[at["left_shoulder"]] + mk[at["right_shoulder"]]) / 2
        centre = (shoulders + (mk[at["left_hip"]] + mk[at["right_hip"]]) / 2) / 2
        read([centre, (centre + shoulders) / 2], "torso")
        inner = cv2.erode(norm.mask.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
        out["border"].extend(skin[norm.mask & ~inner][::4].tolist())
    return out


def main(argv=None) -> int:
    from vidcap.video.fit.cues import SKIN_MIN

    argv = sys.argv[1:] if argv is None else argv
    only = argv[argv.index("--only") + 1] if "--only" in argv else None
    print("The cues' skin likelihood at MediaPipe's landmarks (MediaPipe's masks; mean per "
          f"part; AUC hands+forearms vs torso; torso >= SKIN_MIN {SKIN_MIN})")
    print(f"{'clip':26} {'use':10} " + " ".join(f"{p:>8}" for p in PARTS)
          + f" {'AUC':>5} {'torso>=':>7}")
    aucs = []
    for clip in real_clips():
        if (only and only not in clip.name) or ("--all" not in argv and clip.name not in TUNING):
            continue
        with np.load(clip.reference) as d:
            if "masks" not in d.files:
                continue
        s = clip_samples(clip)
        a = auc(s["hand"] + s["forearm"], s["torso"])
        aucs.append(a)
        use = "tuning" if clip.name in TUNING else "validation"
        print(f"{clip.name:26} {use:10} "
              + " ".join(f"{np.mean(s[p]) if s[p] else np.nan:8.2f}" for p in PARTS)
              + f" {a:5.2f} {np.mean(np.array(s['torso']) >= SKIN_MIN):7.0%}")
    if aucs:
        print(f"mean AUC {np.nanmean(aucs):.2f} over {len(aucs)} clips")
    return 0


if __name__ == "__main__":
    sys.exit(main())
