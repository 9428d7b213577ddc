"""Background plate estimated from the video itself (seed 004 section 3.1.2).

The seed finds "the regions on video frames that do not change" with
Felzenszwalb-Huttenlocher graph segmentation, each region painted with its mean
colour "to decrease the lighting effect". We do the same on a few sampled,
downscaled frames, and combine the regions with per-pixel temporal statistics so
that a pixel the person covers in *most* frames (jumping jacks, waving, turning on
the spot) still takes its background from the frames where it is uncovered:

1. Sample ``n_samples`` frames spread over the video; downscale them to
   ``work_size`` pixels on the long side and normalise each frame's global
   brightness per channel (slow lighting drift).
2. Steps 2-6, the region vote at low resolution, are :mod:`vidcap.video.regionvote`'s.
   Segment each sample (:func:`skimage.segmentation.felzenszwalb`) and replace
   every pixel by its region's mean colour.
3. Per pixel, count for each sample how many other samples show the same region
   colour (within ``tau``, from the data's own noise). The most supported colour is
   the pixel's first guess; pixels whose guess has a majority are *confident*.
4. Region test, per frame: a region whose confident pixels agree with their guess
   (a region that "does not change") is background in that frame, and so are all
   its pixels - including pixels covered in most other frames.
5. The per-pixel vote is repeated with every sample weighted by how background-like
   its region was (step 4), which overturns a person's colour that happened to win
   the plain vote.
6. Motion footprint (:func:`vidcap.video.regionvote._footprint_plate`): the union of
   the pixels that differ from the temporal median in some sample. Inside it, the
   background around it, inpainted across, is a spatial guess that overturns a voted
   colour far from it when a supported sample colour is near it; and a voted colour
   many samples share but unlike every colour of the scene in a ring round the
   footprint (a dark costume before a mottled wall, where the inpainted guess is
   smeared) gives way to the samples that show a colour of the ring
   (:data:`vidcap.video.regionvote.SCENE_RING`). Static areas enclosed by the
   footprint whose ring the limbs cover often (a torso during jumping jacks; "often"
   measured over every frame's time, not the samples: :mod:`vidcap.video.timecover`)
   are body parts that never moved: flagged ``never_seen``, confidence 0.
7. At full resolution, the plate is the median of (at most 9 of) the samples
   each pixel was found to be background in. Pixels never found uncovered are
   flagged (``never_seen``) and inpainted from the surrounding background
   (:func:`cv2.inpaint`), so that the person standing there differs from the plate.
8. Second looks (:func:`vidcap.video.platepass.refine_plate`: self-lit pixels, the
   appearance pass, plate -> person -> plate, a guessed colour no sample shows given
   way to the one most samples show); then (with the still-person passes) a
   plate colour no steady stretch of samples shows gives way to one that stayed
   (:mod:`vidcap.video.steadyscene`); then (:data:`EMPTY_SCENE`,
   :data:`PERSON_BOX`, on by default), samples that show the empty
   scene where the plate holds a person who stood still later (a *ghost*, told by
   its outline: :mod:`vidcap.video.emptyscene`) give the plate back there; where the
   plate holds a colour seen only inside the moving blob of every frame (a walker along
   the line of sight), the frames before the first passer-by and after the last give it
   back (:mod:`vidcap.video.passedby`; off by default,
   :data:`vidcap.video.passedby.PASSED_BY`); and,
   when the plate left part of the frame never seen, a person the plate absorbed is
   looked for with OpenCV's HOG people detector and cut out by ``cv2.grabCut``
   (:mod:`vidcap.video.personbox`; the graph cut's colour models are then learned
   again, the person no longer in the plate). Last (:data:`vidcap.video.absorbed.FLAG_UNSEEN`,
   on), plate pixels in the motion footprint that hold the person's colour and that no
   sample shows in a scene colour (a dancer's back, a standing leg) are flagged never
   seen and inpainted (:func:`vidcap.video.absorbed.flag_unseen`); for a person who stays in
   one place, so are footprint pixels between the person's whose plate and every sample
   are unlike the scene round them, whatever the colour models say (a still torso of the
   floor's colour; :data:`vidcap.video.absorbed.FLAG_STILL`). Then (with the
   still-person passes), where a person came, stood for most of the clip and went, what the
   clip's first and last half second show away from them is taken back
   (:mod:`vidcap.video.stayed`).

``method='median'`` gives the plain per-pixel temporal median as a baseline.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from vidcap.errors import BackgroundError, InputFileError
from vidcap.video.platemedian import _masked_median, _normalised_u8, _robust_plate
from vidcap.video.regionvote import region_vote, work_hw

__all__ = [
    "BackgroundError",
    "BackgroundModel",
    "estimate_background",
    "estimate_plate",
    "load_plate",
    "sample_frames",
]

#: L1 (sum over B, G, R) threshold floor, grey levels: differences below this are
#: never foreground, whatever the measured noise (guards clean synthetic video).
MIN_THRESHOLD = 12.0
#: Foreground threshold in standard deviations of the background's L1 noise above
#: its mean. Isolated false alarms (~1e-4 of pixels at 4) are removed by the 3x3
#: median of the clean-up, so the threshold can stay close to the noise.
K_SIGMA = 4.0


@dataclass(frozen=True)
class BackgroundModel:
    """A background plate and how much to trust it.

    Attributes
    ----------
    plate : numpy.ndarray, shape (H, W, 3), uint8
        Background colour per pixel, BGR, at the video's resolution and at the
        sampled frames' median lighting.
    confidence : numpy.ndarray, shape (H, W), float32
        In [0, 1]: the share of sampled frames in which the pixel was seen as
        background (1 = never covered; 0 = never seen uncovered).
    never_seen : numpy.ndarray, shape (H, W), bool
        Pixels no sampled frame showed uncovered; their plate value is a guess.
    noise_sigma : numpy.ndarray, shape (3,), float32
        Robust (1.4826 MAD) standard deviation of background pixels about the
        plate, per channel B, G, R, grey levels.
    noise_map : numpy.ndarray, shape (H, W), float32
        Per-pixel mean absolute difference (L1 over the channels, grey levels)
        of background samples from the plate; high where the background itself
        flickers (leaves, screens, compression around edges).
    threshold : float
        Suggested foreground threshold on the L1 colour difference (sum over
        B, G, R of ``|frame - plate|``, 0..765), from the noise of pixels known
        to be background.
    method : str
        ``'felzenszwalb'``, ``'median'`` or ``'given'``.
    n_samples : int
        Frames the plate was estimated from.
    moving_fraction : float
        Share of pixels that were not background in at least one sample: ~0 for
        a static scene with nobody in it.
    sample_indices : numpy.ndarray, shape (K,), int
        Frame indices sampled.
    self_lit : numpy.ndarray, shape (H, W), bool, optional
        Pixels that keep their level while the exposure drifts (a lamp, a screen:
        :func:`vidcap.video.stillparts.self_lit`); their plate value is as recorded and
        is compared without the frame's gain.
    still_person : numpy.ndarray, shape (H, W), bool, optional
        Parts of the person that never moved, found by appearance
        (:mod:`vidcap.video.stillparts`): person in a frame where they still look as
        they did (``person_plate``); also in ``never_seen``, their plate inpainted.
    person_plate : numpy.ndarray, shape (H, W, 3), uint8, optional
        The plate before the still parts were inpainted: their own colour.
    colours : numpy.ndarray, shape (2, 4096), float32, optional
        Log-probabilities of the person's and the scene's colours over the clip
        (:func:`vidcap.video.graphcut.clip_colours`), for the silhouette stage's
        graph cut.
    """

    plate: np.ndarray
    confidence: np.ndarray
    never_seen: np.ndarray
    noise_sigma: np.ndarray
    noise_map: np.ndarray
    threshold: float
    method: str
    n_samples: int = 0
    moving_fraction: float = float("nan")
    sample_indices: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    self_lit: np.ndarray | None = None
    still_person: np.ndarray | None = None
    person_plate: np.ndarray | None = None
    colours: np.ndarray | None = None

    @property
    def never_seen_fraction(self) -> float:
        """Share of the frame never seen uncovered, in [0, 1]."""
        return float(self.never_seen.mean())

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) of the plate."""
        return self.plate.shape[:2]

    @classmethod
    def from_plate(cls, plate: np.ndarray, *, noise_sigma: float | None = None):
        """Wrap a known plate (e.g. a photo of the empty scene).

        Parameters
        ----------
        plate : numpy.ndarray, shape (H, W, 3), uint8
            BGR background.
        noise_sigma : float, optional
            Per-channel noise in grey levels; when omitted ``threshold`` is NaN and
            :func:`vidcap.video.silhouette.extract_silhouettes` measures it on the video.
        """
        plate = np.ascontiguousarray(plate)
        if plate.ndim != 3 or plate.shape[2] != 3 or plate.dtype != np.uint8:
            raise ValueError(f"plate must be (H, W, 3) uint8, got {plate.shape} {plate.dtype}")
        h, w = plate.shape[:2]
        sig = np.full(3, np.nan if noise_sigma is None else noise_sigma, np.float32)
        thr = np.nan if noise_sigma is None else _threshold_from_sigma(sig)
        return cls(plate=plate, confidence=np.ones((h, w), np.float32),
                   never_seen=np.zeros((h, w), bool), noise_sigma=sig,
                   noise_map=np.zeros((h, w), np.float32), threshold=float(thr),
                   method="given")


def load_plate(path: str | os.PathLike, video: str | os.PathLike | None = None
               ) -> BackgroundModel:
    """Read a background image (PNG, JPEG, ...) as a :class:`BackgroundModel`; with
    ``video``, ``path`` may instead name frames of it that show the empty scene,
    ``'START:END'`` (:func:`vidcap.video.emptyframes.empty_plate`).

    Raises
    ------
    InputFileError
        The file is missing or not an image; the frames hold none of the video's.
    """
    from vidcap.video.emptyframes import empty_plate, frame_range

    frames = None if video is None else frame_range(path)
    if frames is not None:
        return BackgroundModel.from_plate(empty_plate(video, *frames))
    if not os.path.isfile(path):
        raise InputFileError("no such background image", path)
    data = np.fromfile(path, np.uint8)
    img = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
    if img is None:
        raise InputFileError("not a readable image (PNG, JPEG, BMP, TIFF)", path)
    return BackgroundModel.from_plate(img)


# --------------------------------------------------------------------------- sampling
def sample_frames(
    source, *, n_samples: int = 32, rng: np.random.Generator | None = None, info=None,
) -> tuple[np.ndarray, np.ndarray]:
    """Pick ``n_samples`` frames spread evenly over a video.

    Parameters
    ----------
    source : str, path-like or numpy.ndarray
        A video file, or frames (F, H, W, 3) uint8 BGR.
    n_samples : int
        How many frames at most.
    rng : numpy.random.Generator, optional
        Jitters the sample positions inside their stride; ``None`` = evenly spaced.
    info : vidcap.io.video.VideoInfo, optional
        The video file's :func:`~vidcap.io.video.probe`, when the caller made it (probed
        here otherwise).

    Returns
    -------
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
    indices : numpy.ndarray, shape (K,), int
    """
    if isinstance(source, np.ndarray):
        n = len(source)
        idx = _sample_indices(n, n_samples, rng)
        return np.ascontiguousarray(source[idx]), idx
    from vidcap.io.video import iter_frames, probe

    info = probe(source) if info is None else info
    idx = _sample_indices(info.n_frames, n_samples, rng)
    got, got_idx, start = [], [], 0
    if len(idx) > 1 and np.all(np.diff(idx) == idx[1] - idx[0]):
        # Evenly spaced: only the sampled frames are converted to arrays.
        step = int(idx[1] - idx[0])
        for j, frame in enumerate(iter_frames(source, start=int(idx[0]), step=step)):
            if j >= len(idx):
                break
            got.append(frame)
            got_idx.append(int(idx[j]))
        start = got_idx[-1] + 1 if got_idx else 0
    else:
        wanted = idx.tolist()
        for j, frame in enumerate(iter_frames(source, stop=wanted[-1] + 1, only=set(wanted))):
            got.append(frame)
            got_idx.append(wanted[j])
        start = got_idx[-1] + 1 if got_idx else 0
    if got and any(f.shape != got[0].shape for f in got):
        j = next(j for j, f in enumerate(got) if f.shape != got[0].shape)
        raise BackgroundError(
            f"the frame size changes mid-stream ({got[0].shape[1]}x{got[0].shape[0]}, then "
            f"{got[j].shape[1]}x{got[j].shape[0]} at frame {got_idx[j]}); re-encode the "
            "video at one size", source)
    if 0 < len(got) < len(idx):
        # The container over-stated its frame count: resample what exists.
        return sample_frames(source_frames_cache(source, start), n_samples=n_samples, rng=rng)
    if not got:
        raise BackgroundError("no frames decoded", source)
    return np.stack(got), np.asarray(got_idx)


def source_frames_cache(path, n):  # pragma: no cover - rare: wrong frame counts
    from vidcap.io.video import read_frames

    return read_frames(path, stop=n)


def _sample_indices(n: int, k: int, rng) -> np.ndarray:
    if n <= k:
        return np.arange(n)
    if rng is None:
        # Evenly spaced with a constant stride, centred in the video.
        step = n // k
        return (n - step * (k - 1)) // 2 + step * np.arange(k)
    edges = np.linspace(0, n, k + 1)
    idx = (edges[:-1] + rng.random(k) * np.diff(edges)).astype(int)
    return np.unique(np.clip(idx, 0, n - 1))


# --------------------------------------------------------------------------- estimation
#: Re-take the plate from samples that show the empty scene for at least a second at
#: the clip's start or end (:mod:`vidcap.video.emptyscene`). On by default since the
#: still-person helper gated it by that empty stretch: ``silhouettes_real.py --quick``,
#: median / p10 IoU, cdnet_office_enter (tuning) 0.406 / 0.367 -> 0.901 / 0.768 (with
#: PERSON_BOX), sbi_cavignal (validation) 0.913 -> 0.924, every other validation row
#: unchanged (before the gate it cost 131_01 4-7 s 3/4 p10 0.900 -> 0.824 and
#: pose2sim cam3 0.805 -> 0.427; benchmarks/HISTORY.md, Silhouettes).
EMPTY_SCENE = True
#: Look for a person the plate absorbed with a person detector
#: (:mod:`vidcap.video.personbox`; only when the plate left >= 0.5 % never seen and
#: the person stands still). On by default: cdnet_office_stand (tuning) 0.244 / 0.229
#: -> 0.803 / 0.668 (with EMPTY_SCENE), no validation row changed.
PERSON_BOX = True


#: The seed of the sampler that jitters which frames the plate is estimated from (one at
#: random in each of ``n_samples`` equal stretches), the same in every command (``vidcap
#: convert``, ``silhouettes``, ``pose2d``) and benchmark, so that they estimate the same
#: plate of a clip. Which frames are sampled moves the plate of a person who barely moves
#: a great deal (CMU 02_07 11-14 s front, tuning: median IoU 0.51-0.91 over four seeds,
#: 0.54 evenly spaced, until the footprint's ring test counted time,
#: :data:`vidcap.video.timecover.TIME_COVER`: 0.90-0.92), and neither sampler is better
#: everywhere: evenly spaced frames
#: gave silhouettes_real.py 43 of 50 renders >= 0.92 against 39 of 50, but took the
#: onebyone_room clips' 2D fit (pose2d_real.py, human body) from 9.1 / 6.3 to 18.9 / 11.4 %
#: of height. Seed 0 is what convert's real-clip figures were measured and chosen on.
PLATE_SEED = 0


def plate_rng() -> np.random.Generator:
    """A new generator for :func:`estimate_background`'s ``rng`` seeded by
    :data:`PLATE_SEED`: the frames every command samples for the plate."""
    return np.random.default_rng(PLATE_SEED)


def estimate_plate(source, *, colour_models: bool, still_person: bool,
                   **options) -> BackgroundModel:
    """:func:`estimate_background` as every command runs it (``vidcap convert``,
    ``silhouettes``, ``pose2d``, ``annotate``): the frames of :func:`plate_rng`, the
    colour models for the graph cut when ``colour_models``, the still-person passes
    (``empty_scene``, ``person_box``) when ``still_person``; ``options`` as
    :func:`estimate_background`'s (``method``, ``n_samples``, ``progress``)."""
    return estimate_background(source, rng=plate_rng(), colour_models=colour_models,
                               empty_scene=still_person, person_box=still_person, **options)


def estimate_background(
    source, *, method: str = "felzenszwalb", n_samples: int = 24,
    work_size: int = 160, segment_scale: float = 60.0, min_region: int = 12,
    rng: np.random.Generator | None = None, progress: bool | None = None,
    colour_models: bool = False, empty_scene: bool | None = None,
    person_box: bool | None = None,
) -> BackgroundModel:
    """Estimate the background plate of a static-camera video.

    Parameters
    ----------
    source : str, path-like or numpy.ndarray
        A video file (decoded in chunks) or frames (F, H, W, 3) uint8 BGR.
    method : {'felzenszwalb', 'median'}
        Region stability plus per-pixel votes (see the module docstring), or the
        plain per-pixel temporal median of the samples (a baseline).
    n_samples : int
        Frames sampled (>= 2).
    work_size : int
        Long side, pixels, the samples are downscaled to for segmentation.
    segment_scale : float
        Felzenszwalb's ``scale`` (larger = larger regions), at ``work_size``.
    min_region : int
        Felzenszwalb's ``min_size``, pixels at ``work_size``.
    rng : numpy.random.Generator, optional
        Jitters which frames are sampled (the commands pass :func:`plate_rng`, through
        :func:`estimate_plate`);
        without it the samples are evenly spaced.
    progress : bool, optional
        Show a progress bar (default: when stderr is a terminal).
    colour_models : bool
        Also learn the person's and the scene's colours over the clip
        (``BackgroundModel.colours``), which ``extract_silhouettes(graph_cut=True)``
        needs; about a tenth of the plate's time (``felzenszwalb`` only).
    empty_scene : bool, optional
        Re-take the plate from samples that show the empty scene where it holds a
        person who stood still later (:mod:`vidcap.video.emptyscene`; default
        :data:`EMPTY_SCENE`, on; ``felzenszwalb`` only).
    person_box : bool, optional
        Look for a person the plate absorbed with a person detector
        (:mod:`vidcap.video.personbox`; default :data:`PERSON_BOX`, on;
        ``felzenszwalb`` only).

    Returns
    -------
    BackgroundModel

    Raises
    ------
    BackgroundError
        Fewer than two frames, or nothing ever changes in the video (a static
        scene with nobody in it).
    VideoError
        The file cannot be decoded.
    """
    if method not in ("felzenszwalb", "median"):
        raise ValueError(f"method must be 'felzenszwalb' or 'median', not {method!r}")
    if n_samples < 2:
        raise ValueError("n_samples must be >= 2")
    name = source if not isinstance(source, np.ndarray) else None
    if isinstance(source, np.ndarray):
        if source.ndim != 4 or source.shape[-1] != 3 or source.dtype != np.uint8:
            raise ValueError(f"frames must be (F, H, W, 3) uint8, got {source.shape}")
        if len(source) == 0:
            raise BackgroundError("the video has no frames")
    info = None
    if name is not None:
        from vidcap.io.video import probe

        info = probe(source)  # once: the samples' positions and the empty scene's times
    frames, idx, thumbs = _sampled(source, method, n_samples, rng, info, work_size)
    from vidcap.video import timecover

    cover = timecover.motion_cover(thumbs) if thumbs is not None else None
    from vidcap.video.inputchecks import check_samples

    check_samples(frames, name)

    gains = _frame_gains(frames)
    if method == "median":
        weights = np.ones(frames.shape[:3], np.float32)
        plate = _gain_median(frames, gains)
        conf = np.ones(frames.shape[1:3], np.float32)
        model = _finish(frames, gains, plate, weights, conf, "median", idx, name)
        return model
    weights_small, holes = region_vote(frames, gains, work_size=work_size,
                                 segment_scale=segment_scale, min_region=min_region,
                                 progress=progress, cover=cover)
    model = _finish_regions(frames, gains, weights_small, idx, name, holes)
    from vidcap.video.appearance import small_samples
    from vidcap.video.platepass import refine_plate

    # (the colour passes' samples at their working size, made once for all of them)
    small = small_samples(frames, gains)
    model = refine_plate(model, frames, gains, weights_small.shape[1:],
                         colour_models=colour_models, small=small)
    n = len(source) if info is None else info.n_frames
    still = EMPTY_SCENE if empty_scene is None else empty_scene
    return _later_passes(model, (frames, gains, small), thumbs, info, n, still,
                         PERSON_BOX if person_box is None else person_box)


def _later_passes(model, samples, thumbs, info, n: int, still: bool, person_box: bool):
    """Step 8's passes after :func:`vidcap.video.platepass.refine_plate` (module
    docstring), in their order: the plate's unsteady colours and the empty scene (with
    ``still``, the still-person passes), the passed-by colours, the absorbed person
    (with ``person_box``), the unseen flags, the never-seen pixels' second steady state
    and, last, the person who came, stayed and went (with ``still``); ``n`` frames in the
    clip, ``thumbs`` every frame's thumbnail or None; ``samples`` the plate's samples,
    their gains and the colour passes' small samples
    (:func:`vidcap.video.appearance.small_samples`)."""
    frames, gains, small = samples
    if still:
        model = _steady_pass(model, samples, info, never=False)
        from vidcap.video.emptyscene import plate_from_empty

        fps = _fps(info)
        idx = model.sample_indices
        model = plate_from_empty(model, frames, gains, times=idx / fps,
                                 ends=(0.0, max(n - 1, int(idx[-1])) / fps))
    from vidcap.video import passedby, stayed

    if thumbs is not None and passedby.PASSED_BY:
        model = _thumbnail_pass(model, samples, thumbs, info, n,
                                passedby.retake_passed_by)
    if person_box:
        from vidcap.video.heldpose import absorbed_or_held

        found = absorbed_or_held(model, frames, gains)
        if found is not model and model.colours is not None:
            # The person's colours were learned while the plate held the still person
            # (05_04 front: the trousers were scene to them, and the cut took the legs
            # out): learn them again now that the person differs from the plate.
            from vidcap.video.graphcut import clip_colours

            found = replace(found, colours=clip_colours(found, frames, gains, small))
        model = found
    from vidcap.video import absorbed

    if absorbed.FLAG_UNSEEN:
        model = absorbed.flag_unseen(model, frames, gains, small=small)
    if still:
        model = _steady_pass(model, samples, info, unsteady=False)
    if thumbs is not None and stayed.STAYED and still:
        # (last: the passes before it flag never seen, and guess, what it takes back)
        model = _thumbnail_pass(model, samples, thumbs, info, n,
                                stayed.retake_stayed)
    return model


def _steady_pass(model, samples, info, **rules):
    """``model`` after :func:`vidcap.video.steadyscene.retake_steady` (``rules``: its
    ``never`` and ``unsteady`` keywords), the colour models learned again when the
    never-seen rule changed the plate; ``samples`` as :func:`_later_passes`'."""
    from vidcap.video.steadyscene import retake_steady

    frames, gains, small = samples
    found = retake_steady(model, frames, gains, model.sample_indices / _fps(info), **rules)
    # (the unsteady colours are a few pixels: the colour models learned on the plate before
    # them serve, and learning them again cost the 1000x1000 clip's convert 1.6 s)
    if found is not model and model.colours is not None and rules.get("never", True):
        from vidcap.video.graphcut import clip_colours

        found = replace(found, colours=clip_colours(found, frames, gains, small))
    return found


def _thumbnail_pass(model, samples, thumbs, info, n: int, retake):
    """``model`` after ``retake`` (a pass over every frame's thumbnail:
    :func:`vidcap.video.passedby.retake_passed_by`,
    :func:`vidcap.video.stayed.retake_stayed`), the colour models learned again when the
    plate changed (they were learned against the old plate); ``n`` frames in the clip;
    ``samples`` as :func:`_later_passes`'."""
    from vidcap.video.timecover import thumbnail_step

    frames, gains, small = samples
    found = retake(model, frames, gains, thumbs, fps=_fps(info), step=thumbnail_step(n))
    if found is not model and model.colours is not None:
        from vidcap.video.graphcut import clip_colours

        found = replace(found, colours=clip_colours(found, frames, gains, small))
    return found


def _sampled(source, method: str, n_samples: int, rng, info, work_size: int):
    """The plate's samples (F, H, W, 3), their frame indices (F,) and, for the region
    method with :data:`vidcap.video.timecover.TIME_COVER`, every frame (every
    :func:`~vidcap.video.timecover.thumbnail_step`-th) at the working size (N, h, w, 3)
    uint8 (else None; None too for fewer than two), from one decoding pass."""
    from vidcap.video import timecover

    if method != "felzenszwalb" or not timecover.TIME_COVER:
        frames, idx = sample_frames(source, n_samples=n_samples, rng=rng, info=info)
        return frames, idx, None
    hw = source.shape[1:3] if info is None else (info.height, info.width)
    frames, idx, thumbs = _samples_and_thumbnails(source, n_samples, rng, info,
                                                  work_hw(hw, work_size))
    return frames, idx, thumbs if len(thumbs) >= 2 else None



def _samples_and_thumbnails(source, n_samples, rng, info, hw):
    """:func:`sample_frames`'s samples and indices, and every frame (every
    :func:`vidcap.video.timecover.thumbnail_step`-th of a long clip) at ``hw`` (h, w),
    uint8, from one decoding of the file."""
    from vidcap.video.timecover import thumbnail_step

    h, w = hw
    if isinstance(source, np.ndarray):
        frames, idx = sample_frames(source, n_samples=n_samples, rng=rng)
        every = source[::thumbnail_step(len(source))]
        return frames, idx, np.stack([cv2.resize(f, (w, h), interpolation=cv2.INTER_AREA)
                                      for f in every])
    from vidcap.io.video import iter_thumbnails

    idx = _sample_indices(info.n_frames, n_samples, rng)
    wanted = set(idx.tolist())
    got, got_idx, thumbs = [], [], []
    for i, thumb, frame in iter_thumbnails(source, (w, h), every=thumbnail_step(info.n_frames),
                                           only=wanted):
        if thumb is not None:
            thumbs.append(thumb)
        if frame is not None:
            got.append(frame)
            got_idx.append(i)
    if len(got) < len(idx) or any(f.shape != got[0].shape for f in got):
        # (a frame count the container over-states, a size that changes: as sample_frames
        # says and does)
        frames, idx = sample_frames(source, n_samples=n_samples, rng=rng, info=info)
        return frames, idx, np.stack(thumbs) if thumbs else np.zeros((0, h, w, 3), np.uint8)
    return np.stack(got), np.asarray(got_idx), np.stack(thumbs)


def _fps(info) -> float:
    """The frame rate of the video ``info`` (:func:`vidcap.io.video.probe`) describes;
    :data:`vidcap.video.emptyscene.ASSUMED_FPS` for frames given as an array (None) or
    a rate the container does not give."""
    from vidcap.video.emptyscene import ASSUMED_FPS

    fps = None if info is None else info.fps
    return float(fps) if fps and np.isfinite(fps) and fps > 0 else ASSUMED_FPS


def _frame_gains(frames: np.ndarray) -> np.ndarray:
    """Per-frame, per-channel brightness relative to the samples' median frame, (K, 3)."""
    step = max(1, int(np.sqrt(frames.shape[1] * frames.shape[2] / 4096)))
    sub = frames[:, ::step, ::step].astype(np.float32) + 1.0
    med = np.median(sub, axis=0)
    ratio = sub / med
    g = np.median(ratio.reshape(len(frames), -1, 3), axis=1)
    return np.clip(g, 0.25, 4.0).astype(np.float32)


def _gain_median(frames, gains) -> np.ndarray:
    return _masked_median(_normalised_u8(frames, gains), None)




def _finish_regions(frames, gains, weights_small, idx, name, holes=None):
    k, hh, ww = frames.shape[:3]
    h, w = weights_small.shape[1:]
    # Keep only samples well inside background regions (low resolution edges are
    # coarse), unless that leaves a pixel with none.
    binary = (weights_small > 0).astype(np.uint8)
    eroded = np.stack([cv2.erode(b, np.ones((3, 3), np.uint8)) for b in binary])
    keep_small = np.where(eroded.any(axis=0), eroded, binary)
    # 0/1 per sample and pixel: uint8, not float32 (4x less memory at full resolution)
    wfull = np.stack([cv2.resize(x, (ww, hh), interpolation=cv2.INTER_NEAREST)
                      for x in keep_small])
    seen = wfull.sum(axis=0, dtype=np.int32)
    never = seen <= 0
    conf = (seen / k).astype(np.float32)
    plate = _robust_plate(frames, gains, wfull)
    if never.any():
        # Never seen uncovered: guess from the surrounding background, so that
        # whatever stands there (the person) still differs from the plate.
        # Static body parts come from the low-resolution footprint: widen them by
        # one low-res pixel so that the inpainting starts from background, not
        # from the person's edge.
        ring = never.astype(np.uint8)
        if holes is not None and holes.any():
            r = int(np.ceil(hh / h)) + 1
            body = cv2.resize(holes.astype(np.uint8), (ww, hh),
                              interpolation=cv2.INTER_NEAREST)
            ring |= cv2.dilate(body, np.ones((2 * r + 1, 2 * r + 1), np.uint8))
        plate = cv2.inpaint(plate, ring, 5, cv2.INPAINT_TELEA)
    return _finish(frames, gains, plate, wfull, conf, "felzenszwalb", idx, name,
                   never_seen=never)


def _finish(frames, gains, plate, weights, conf, method, idx, name, never_seen=None):
    """Noise estimates from background samples; the static-scene check."""
    k = len(frames)
    full_hw = plate.shape[:2]
    # Statistics on every other pixel of large frames: 4x less work, same noise;
    # every 3rd from 4.5 Mpixel, every 4th at 4K (1080p and less: every other).
    n_px = plate.shape[0] * plate.shape[1]
    st = max(2, int(np.sqrt(n_px / 500_000))) if n_px > 100_000 else 1
    frames = frames[:, ::st, ::st]
    weights = weights[:, ::st, ::st]
    ref = plate[::st, ::st].astype(np.float32)[None] * gains[:, None, None, :]
    resid = frames.astype(np.float32) - ref  # (K, h, w, 3)
    l1 = _l1(resid)
    bgw = weights > 0
    if method == "median":
        # Background = close to the median; the bulk of pixels in most frames.
        bgw = l1 < max(3.0 * 1.4826 * float(np.median(l1)) + 6.0, MIN_THRESHOLD)
        conf = _upsample(bgw.mean(axis=0).astype(np.float32), full_hw)
    # The background samples' residuals, every n-th of them: their positions first
    # (``resid[bgw]`` copied all of them, ~0.9 s of CPU for 24 samples at 1000x1000).
    at = np.flatnonzero(bgw)
    if len(at) < 16:
        at = np.arange(bgw.size)
    if len(at) > 200_000:  # plenty for a robust spread; the median is the cost
        at = at[:: len(at) // 200_000]
    sel = resid.reshape(-1, 3)[at]
    sigma = (1.4826 * np.median(np.abs(sel - np.median(sel, axis=0)), axis=0)).astype(
        np.float32)
    thr = _threshold_from_sigma(sigma, l1[bgw] if bgw.any() else l1.ravel())
    cnt = bgw.sum(axis=0)
    # Mean over background samples of the difference, clipped at twice the
    # threshold so a stray person pixel counted as background cannot inflate it.
    clipped = np.minimum(l1, 2 * thr) * bgw
    noise_map = np.where(cnt > 0, clipped.sum(axis=0) / np.maximum(cnt, 1), 0.0)
    noise_map = cv2.dilate(_upsample(noise_map.astype(np.float32), full_hw),
                           np.ones((3, 3), np.uint8))
    # Static-scene check: pixels far from the plate in some sample (beyond the
    # threshold), in connected areas large enough to be a person.
    moving = (l1 > 2 * thr).any(axis=0)
    moving = cv2.morphologyEx(moving.astype(np.uint8), cv2.MORPH_OPEN,
                              np.ones((3, 3), np.uint8)).astype(bool)
    moving_fraction = float(moving.mean())
    if moving_fraction < 2e-4:
        raise BackgroundError(
            f"nothing moves in the {k} sampled frames: nobody in view, or a person who "
            "never moves (then give a photo of the empty scene: --background plate.png)",
            name)
    if never_seen is None:
        never_seen = np.zeros(full_hw, bool)
    return BackgroundModel(
        plate=plate, confidence=np.clip(conf, 0, 1).astype(np.float32),
        never_seen=never_seen, noise_sigma=sigma, noise_map=noise_map.astype(np.float32),
        threshold=float(thr), method=method, n_samples=k,
        moving_fraction=moving_fraction, sample_indices=np.asarray(idx))


def _l1(resid: np.ndarray) -> np.ndarray:
    """``np.abs(resid).sum(axis=-1)`` of (..., 3) float32 residuals, the same values: the
    channels added in the order NumPy's reduction adds them, as three whole-array
    additions (a reduction over a 3-long axis runs an inner loop per pixel, ~7x
    slower)."""
    a = np.abs(resid)
    return a[..., 0] + a[..., 1] + a[..., 2]


def _upsample(img: np.ndarray, hw) -> np.ndarray:
    if img.shape[:2] == tuple(hw):
        return img
    return cv2.resize(img, (hw[1], hw[0]), interpolation=cv2.INTER_NEAREST)


def _threshold_from_sigma(sigma, l1=None) -> float:
    """Foreground threshold on the L1 colour difference from background noise.

    With Gaussian noise of standard deviation s per channel, the L1 difference
    over three channels has mean ~2.39 s and standard deviation ~1.04 s; the
    threshold sits K_SIGMA standard deviations above the mean (robustly measured when
    the background differences ``l1`` are given), and never below MIN_THRESHOLD.
    """
    s = float(np.sqrt(np.mean(np.square(np.nan_to_num(sigma, nan=0.0)))))
    t = 2.39 * s + K_SIGMA * 1.04 * s
    if l1 is not None and np.size(l1):
        sub = np.asarray(l1).ravel()
        if sub.size > 200_000:
            sub = sub[:: sub.size // 200_000]
        m = float(np.median(sub))
        mad = 1.4826 * float(np.median(np.abs(sub - m)))
        t = max(t, m + K_SIGMA * mad)
    return float(max(t, MIN_THRESHOLD))
