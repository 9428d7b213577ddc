"""One output guard for every command: no output may be an input (explicit, implicit,
through a link) or another output; refused before any work, inputs untouched."""

from __future__ import annotations

import os
import shutil

import pytest

from tests.hostile.mutate import digest
from vidcap.cli import main


@pytest.fixture
def files(tmp_path, shared_data):
    a, b = tmp_path / "a.c3d", tmp_path / "b.c3d"
    shutil.copy(shared_data("c3d/07_01.c3d"), a)
    shutil.copy(shared_data("c3d/02_01.c3d"), b)
    ms = tmp_path / "set.toml"
    ms.write_text("# a marker set file\n")
    video = tmp_path / "v.mp4"
    shutil.copy(_sample(), video)
    ann = tmp_path / "v.vidcap.json"
    ann.write_text('{"version": 1, "events": []}\n')
    return {"a": a, "b": b, "ms": ms, "video": video, "ann": ann, "dir": tmp_path}


def _sample():
    from pathlib import Path

    return Path(__file__).resolve().parents[2] / "sample_videos" / "walk_side.mp4"


def _refused(capsys, argv, *, named, says):
    err = capsys.readouterr()
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2, err
    assert len(err) == 1 and err[0].startswith(f"vidcap: error: {named}"), err
    assert says in err[0], err
    return err[0]


CASES = {
    "joints -o an --also trial": (lambda f: ["joints", f["a"], "--also", f["b"], "-o", f["b"]],
                                  "b", "an --also trial"),
    "joints -o the marker set": (lambda f: ["joints", f["a"], "--markerset", f["ms"], "-o",
                                            f["ms"]], "ms", "--markerset"),
    "convert -o the default annotations": (lambda f: ["convert", f["video"], "-o", f["ann"]],
                                           "ann", "annotations read by default"),
    "convert --save = -o": (lambda f: ["convert", f["video"], "-o", f["dir"] / "x.bvh",
                                       "--save", f["dir"] / "x.bvh"], None, "both -o and --save"),
    "joints --centres = -o": (lambda f: ["joints", f["a"], "-o", f["dir"] / "j.bvh",
                                         "--centres", f["dir"] / "j.bvh"], None,
                              "both -o and --centres"),
    "joints --report = --centres": (lambda f: ["joints", f["a"], "--report", f["dir"] / "r",
                                               "--centres", f["dir"] / "r"], None, "both"),
    "joints -o the trial": (lambda f: ["joints", f["a"], "-o", f["a"]], "a", "the trial"),
    "joints --draft-markerset the trial": (lambda f: ["joints", f["a"], "--draft-markerset",
                                                      f["a"]], "a", "the trial"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_output_clash_is_refused_before_any_work(case, files, capsys):
    argv_of, victim, says = CASES[case]
    argv = argv_of(files)
    before = digest([p for p in files.values() if p.is_file()])
    listing = sorted(os.listdir(files["dir"]))
    named = str(files[victim]) if victim else str(files["dir"])
    _refused(capsys, argv, named=named, says=says)
    assert digest([p for p in files.values() if p.is_file()]) == before
    assert sorted(os.listdir(files["dir"])) == listing


def test_a_link_to_an_input_is_the_input(files, capsys):
    link = files["dir"] / "link.c3d"
    link.symlink_to(files["b"])
    hard = files["dir"] / "hard.c3d"
    os.link(files["a"], hard)
    _refused(capsys, ["joints", files["a"], "--also", files["b"], "-o", link],
             named=str(link), says="an --also trial")
    _refused(capsys, ["joints", files["a"], "-o", hard], named=str(hard), says="the trial")
    # a link to a folder, then the input's name inside it
    (files["dir"] / "sub").mkdir()
    (files["dir"] / "alias").symlink_to(files["dir"])
    _refused(capsys, ["joints", files["a"], "-o", files["dir"] / "alias" / "a.c3d"],
             named=str(files["dir"] / "alias" / "a.c3d"), says="the trial")


def test_background_image_is_an_input(files, capsys):
    plate = files["dir"] / "plate.png"
    plate.write_bytes(b"png")
    _refused(capsys, ["convert", files["video"], "--background", plate, "-o", plate],
             named=str(plate), says="--background")


def test_review_png_folder_that_is_an_input(files, capsys):
    npz = files["dir"] / "r.npz"
    npz.write_bytes(b"x")
    _refused(capsys, ["review", files["video"], "--from", npz, "--png", files["video"]],
             named=str(files["video"]), says="folder")


def test_batch_outputs_that_collide(tmp_path, capsys):
    src = _sample()
    (tmp_path / "p").mkdir()
    (tmp_path / "q").mkdir()
    for name in ("p/x.mp4", "q/x.mp4", "x_1.mp4"):
        shutil.copy(src, tmp_path / name)
    out = tmp_path / "out"
    code = main(["batch", str(tmp_path / "p" / "x.mp4"), str(tmp_path / "q" / "x.mp4"),
                 str(tmp_path / "x_1.mp4"), "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "x_1.bvh" in err[0], err
    assert not list(out.glob("*.bvh"))
