"""The plate's still-person passes in ``vidcap convert`` / ``api.convert`` / the pipeline:
the option, its default and the plate stage's cache key (issue 26)."""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from tests.test_silhouettes_cli import still_block_clip
from vidcap.video import pipeline
from vidcap.video.annotations import Annotations


def _iou(a, b):
    return (a & b).sum((1, 2)) / np.maximum((a | b).sum((1, 2)), 1)


def test_convert_still_person_finds_a_block_that_stood_still_after_an_empty_stretch(
        cli, tmp_path):
    """``vidcap convert --still-person``: the saved silhouettes hold the block that
    stood still after the empty stretch; ``--no-still-person`` misses it (the plate
    keeps the block)."""
    video, _, truth = still_block_clip(tmp_path)
    ious = {}
    for flag in ("--no-still-person", "--still-person"):
        npz = tmp_path / f"s{flag}.npz"
        r = cli("convert", video, "-o", tmp_path / f"o{flag}.bvh", "--save", npz,
                "--no-cache", "--jobs", "1", flag)
        assert r.returncode == 0, r.stderr
        with np.load(npz) as z:
            ious[flag] = _iou(z["masks"][10:], truth[10:])
    assert np.median(ious["--still-person"]) >= 0.8
    assert np.median(ious["--still-person"]) > np.median(ious["--no-still-person"]) + 0.2


def test_the_plate_cache_keys_the_still_person_passes(tmp_path):
    """Each setting has its own plate entry (and silhouettes); a second run with the
    same setting reads it back, the still parts' own colour included."""
    video, _, truth = still_block_clip(tmp_path)
    cache = tmp_path / "cache"
    got, said = {}, []
    for still in (False, True):
        got[still] = pipeline.silhouettes_only(video, Annotations(), cache_dir=cache,
                                               still_person=still, log=said.append)
    assert len(list(cache.glob("plate-*.npz"))) == 2
    assert len(list(cache.glob("silhouettes-*.npz"))) == 2
    assert np.median(_iou(got[True].masks[10:], truth[10:])) > np.median(
        _iou(got[False].masks[10:], truth[10:])) + 0.2
    said.clear()
    again = pipeline.silhouettes_only(video, Annotations(), cache_dir=cache,
                                      still_person=True, log=said.append)
    assert not any("estimating" in m for m in said)
    np.testing.assert_array_equal(again.masks[:], got[True].masks[:])


def test_a_cached_plate_keeps_the_still_parts_own_colour(tmp_path, monkeypatch):
    """``person_plate`` (the still parts' colour before the plate was inpainted) goes
    through the stage cache; an entry without it is recomputed."""
    from vidcap.video.background import BackgroundModel
    from vidcap.video.stagecache import StageCache

    rng = np.random.default_rng(0)
    plate = rng.integers(0, 255, (8, 10, 3), dtype=np.uint8)
    still = np.zeros((8, 10), bool)
    still[2:5, 3:6] = True
    own = rng.integers(0, 255, (8, 10, 3), dtype=np.uint8)
    model = replace(BackgroundModel.from_plate(plate, noise_sigma=2.0), still_person=still,
                    person_plate=own, never_seen=still)
    cache = StageCache(tmp_path)
    calls = []

    def fake_estimate(video, **kw):
        calls.append(kw)
        return model

    import vidcap.video.background as background

    monkeypatch.setattr(background, "estimate_background", fake_estimate)
    for _ in range(2):
        back = pipeline._plate_of(cache, "k", tmp_path / "v.mp4", None, progress=False,
                                  log=lambda m: None, colour_models=False, still_person=True)
    assert len(calls) == 1 and calls[0]["empty_scene"] and calls[0]["person_box"]
    np.testing.assert_array_equal(back.person_plate, own)
    np.testing.assert_array_equal(back.still_person, still)


def test_convert_flag_default_agrees_with_the_pipeline(monkeypatch):
    from vidcap.commands import convert as convert_cmd
    from vidcap.video import background

    assert convert_cmd.DEFAULT_STILL_PERSON == pipeline.default_still_person()
    ap = argparse.ArgumentParser()
    convert_cmd.add_arguments(ap)
    assert ap.parse_args(["v.mp4", "-o", "o.bvh", "--still-person"]).still_person is True
    assert ap.parse_args(["v.mp4", "-o", "o.bvh", "--no-still-person"]).still_person is False
    assert ap.parse_args(["v.mp4", "-o", "o.bvh"]).still_person is None
    # the default follows the two passes' module switches; a given plate turns it off
    monkeypatch.setattr(background, "EMPTY_SCENE", True)
    monkeypatch.setattr(background, "PERSON_BOX", True)
    assert pipeline._still_person_option(None, None, print) is True
    said = []
    assert pipeline._still_person_option(True, "plate.png", said.append) is False
    assert said and "given" in said[0]
    monkeypatch.setattr(background, "PERSON_BOX", False)
    assert pipeline._still_person_option(None, None, print) is False
