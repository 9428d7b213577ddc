"""2D pose by fitting the 10-cylinder model to a silhouette (seed 004 section 3.1.4).

This module is the fit's overview and its public names (re-exported from the
modules that hold them). Where each part lives:

* :mod:`vidcap.video.fit.frame` - one frame's fit: the order below (:func:`fit_pose`).
* :mod:`vidcap.video.fit.tracking` - a clip: tracking and the temporal priors
  (:func:`fit_sequence`, :func:`body_heights`).
* :mod:`vidcap.video.fit.state` - the pose being fitted, a frozen :class:`FitState`, and
  :func:`~vidcap.video.fit.state.keep_if_better`; :mod:`vidcap.video.fit.engine` - what every
  move of one silhouette's fit reads (``_MaskEngine``).
* The moves, each ``(engine, state) -> state``: :mod:`vidcap.video.fit.torso` (steps 2-3),
  :mod:`vidcap.video.fit.limbs` (steps 4-5 and the refinement), :mod:`vidcap.video.fit.legs`
  (step 6, crossings), :mod:`vidcap.video.fit.foreshortening` (step 7),
  :mod:`vidcap.video.fit.moves` (Algorithm 1, group, spread and shift searches),
  :mod:`vidcap.video.fit.grids` (whole-limb grids), :mod:`vidcap.video.fit.labels` (limb names),
  :mod:`vidcap.video.fit.crossing` (legs passing each other in a track).
* :mod:`vidcap.video.fit.result` - :class:`FramePose` and :class:`Pose2D` and their I/O;
  :mod:`vidcap.video.fit.options` - :class:`~vidcap.video.fit.options.FitOptions`.

The order of section 3.1.4, per frame (:func:`fit_pose` with ``previous=None``):

1. Normalise the silhouette to a fixed height (section 4.2), so the body height in
   pixels is the silhouette's height and every length follows Table 3.1.
2. Torso position: the pelvis' y from the Table 3.1 ratios (head + torso below the
   top of the silhouette), its x the horizontal middle of the silhouette (the median
   over the torso's scan lines of the middle of each line's widest run).
3. Torso angle with the head attached (Algorithm 1, Table 3.3 "Waist" limits), then
   the head angle (Algorithm 1, "Neck" limits).
4. Arms by contour analysis (Algorithms 2-4): the silhouette left over beside the
   fitted torso and head, on each side, ordered into a curve away from the shoulder
   and split at the elbow corner.
5. Lower legs by scan-line contour analysis (Algorithm 2), knee crossing
   (Algorithm 5) and swap.
6. Upper legs with their lower legs as one unit (Algorithm 1, "hip" limits).
7. Foreshortening of every segment (Algorithm 6).

Beyond the seed:

* Segments are drawn as rectangles (``caps=False``, the default) or capsules; the
  renderer's cylinders seen from the side are rectangles, and rectangles measured
  better on rendered clips (RESULTS.md).
* Torso: after the seed's torso+head and head searches, the model is shifted so
  the head lines up with the silhouette and the torso is searched again turning
  about the neck (the silhouette's middle is pulled by arms and legs; the head is
  not), so a leaning torso under an upright head is found.
* Bodies far from upright (issue 27 item 4): a fresh fit with S below 0.7 or a torso
  35 degrees or more from upright is fitted again with the torso turned about a neck
  placed under the head over 15-165 degrees (:func:`vidcap.video.fit.torso.fit_torso_lean`,
  the seed's limits are 45-135), and the better fit kept; a tracked frame below S 0.7
  is challenged by a fresh fit. The searches about the neck reach 15-165 degrees.
* Arms: residual slivers along the torso's edges are removed (an opening about an
  arm's width) before the contour curves are built; the curves are rings of
  distance from the shoulder rather than horizontal scan lines, so a raised or
  horizontal arm gives a curve too.
* ``spread``: how far the shoulders and hips sit from the torso axis (0 side view,
  1 front view) is searched like a foreshortening ratio (the seed draws one view).
* When Algorithm 5 reports crossed legs, both leg assignments are fitted and the
  better one kept; near-ties go to the straighter legs (the seed always swaps).
* ``refine`` (default on): the whole model is centred (shift search), each arm is
  searched whole (lower arm rigid, within 90 degrees of the contour estimate) and
  its length (Algorithm 6 on the arm as a unit), then every limb segment again
  with Algorithm 1 against the whole silhouette (+-30 degrees; lower limbs within
  150 degrees of their parent, thighs over 180-360 degrees rather than Table 3.3's
  240-300 so high steps fit), the torso once more with every limb drawn, and the
  final Algorithm 6 pass starts from the current ratios.
* ``arm_grid`` (default on, with ``refine``): after the limb refinement each whole arm
  is scored at every (upper, lower) angle pair 15 degrees apart in one batch
  (:func:`vidcap.video.fit.grids.search_arm_grid`), so a forearm poking out far from the
  contour estimate (raised beside the head, bent forward) is found; near-ties (an arm
  inside the torso's silhouette covers the same pixels at any angle) go to the arm
  hanging along the torso. Run on fresh fits only: in tracked frames it measured worse
  (it re-places carried arms on slivers along the torso's edges), so warm frames carry
  their arms from the previous frame, and ``arm_track`` (default off: on real clips it
  lost, tfjs_dance 5.5 -> 7.9 % of height) searches them in a narrower grid: each whole
  arm at full length, the upper arm within 30 degrees of the track's, the forearm
  anywhere within the 150-degree bend, kept only when it fits better than the carried
  arm by more than 10 pixels' worth of S
  (:func:`vidcap.video.fit.grids.search_arm_track`; a forearm raised faster than the
  track's +-16 degrees a frame was left behind and shrunk by Algorithm 6).
  ``refine=False`` (``--no-refine``) runs the seed's order only.
* ``arm_pairs`` (default on, with ``arm_grid``): after the two arm grids both arms are
  searched together (:func:`vidcap.video.fit.armpairs.search_arm_pairs`): each arm's six
  best grid pairs (the other arm left out), the arm in place and the arm hanging, paired
  and scored with both arms drawn, less a prior of 12 pixels' worth of S per radian an
  arm segment hidden whole by the torso turns away from hanging. Arm by arm, a
  three-quarter view's far arm folded across the chest to cover the near elbow's bulge
  (free inside the torso) and the near arm, scored with the fold in place, never took
  it back (walk_three_quarter's far wrist 17-44 % of the height off in frames 41-54).
* ``leg_grid`` (default on): in tracked frames each whole leg is scored at every
  (thigh, shin) angle pair 15 degrees apart in one batch
  (:func:`vidcap.video.fit.grids.search_leg_grid`) and the best kept when it fits better than the
  tracked leg by more than 3 pixels' worth of S, so a leg that swung beyond the
  track's +-8 degrees (a knee raised across the other leg) is found again.
* ``fold_legs`` (default off: a real squat facing the camera lost): in a frame whose
  silhouette is under 0.92 of the model's height (a crouch, a squat), each thigh is
  searched again at 45 % of its length, its shin re-hung from the new knee, and kept
  when S rises by more than the tie (:func:`vidcap.video.fit.fold.fold_thighs`): a
  thigh pointing at the camera is short in the image, and Algorithm 1 at full length
  turns it elsewhere before Algorithm 6 can shorten it. A tracked crouching frame also
  searches the torso's foreshortening (+-0.3).
* ``track_bend`` (default on): a tracked frame whose torso leans 20 degrees or more, or
  whose silhouette is under 0.92 of the model's height, also moves the model up and
  down and turns the torso (head attached) about the pelvis, +-24 degrees within
  15-165 (:func:`vidcap.video.fit.bend.track_bend`): a body bending over keeps its
  hips where the legs hold them while the neck swings down, and the track, which
  turned the torso about a neck placed for an upright body, kept an upright torso
  poking out above the outline.
* Tracking (:func:`fit_sequence`, ``tracked=True``): a frame whose silhouette is
  still covered by the previous frame's pose (S >= ``warm_threshold``) starts every
  search from that pose with narrow intervals, skips the contour analysis, and
  searches the four upper limbs, then the head and four lower limbs, then all
  ratios in lockstep (one batch per iteration for a whole group,
  :func:`vidcap.video.fit.moves.search_group`). Limbs then keep their labels through crossings. A
  warm fit losing more than 3 % of the previous frame's S is redone from scratch
  and the better kept, and 10 frames after the last fresh fit another one challenges
  the track (so a wrong but stable track is left;
  :data:`vidcap.video.fit.tracking.REINIT_EVERY`). In a side view (spread < 0.3)
  a fresh fit that takes over keeps the track's limb names
  (:func:`vidcap.video.fit.labels.keep_labels`): its image-side names would swap the
  legs against the frames before after every crossing.
  With the hips apart (spread >= 0.4) a tracked frame also tries its legs exchanged
  between the hips (or the ankles, or the knees) and keeps what fits best by S and by
  where the last two frames' knees and ankles were heading, forward and then backward
  within each track (:mod:`vidcap.video.fit.crossing`: legs passing each other).
  ``tracked=False`` (``--per-frame``) fits every frame independently, as the seed does.
* Temporal priors in tracked mode (:func:`fit_sequence`): when a fresh fit replaces
  the track, the frames before it are re-tracked backward from it while that fits
  them better (a track that began in a wrong pose is corrected from where the right
  one was found; where the carried pose slips, a fresh fit of the frame that beats it
  and the stored fit is kept and carried on instead); and a frame whose ``spread``
  jumps away from its neighbours' running median is refitted with the spread fixed at
  that median.
* Warm starts take part in their own search's first batch, so a search never ends
  below where it started.

Left and right
--------------
During 2D fitting ``l_*`` and ``r_*`` do NOT mean the performer's left and right.
Per frame (seed 004 section 3.1.4) ``l_*`` is the limb on the image's left. In
tracked mode a limb keeps its label from the frame where tracking (re)started, where
it was the image-left one, so labels follow limbs through crossings. The 3D stage
assigns true sides from the body orientation.

Angles are image-plane angles in radians, counter-clockwise from the image's +x axis
with y up (``pi/2`` straight up, ``3 pi/2`` straight down), in [0, 2 pi), of the
vector from the segment's proximal to its distal joint; the same convention as
:data:`vidcap.body.IMAGE_ANGLE_LIMITS_DEG` (which is in degrees).
"""

from vidcap.video.fit.frame import fit_normalised, fit_pose
from vidcap.video.fit.labels import LIMB_PAIRS
from vidcap.video.fit.result import FramePose, Pose2D
from vidcap.video.fit.tracking import body_heights, fit_sequence

__all__ = ["LIMB_PAIRS", "FramePose", "Pose2D", "body_heights", "fit_normalised", "fit_pose",
           "fit_sequence"]
