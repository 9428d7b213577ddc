"""Output paths are checked before any work: a folder, a path under a file, an input."""

from __future__ import annotations

import pytest

from vidcap.cli import main
from vidcap.errors import UsageError
from vidcap.fileio import atomic_path, check_output_file


@pytest.fixture
def video(tmp_path):
    # the checks run before the input is opened, so any file stands in for the video
    p = tmp_path / "clip.mp4"
    p.write_bytes(b"not decoded by these tests")
    return p


def _error(capsys, argv):
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err.strip().splitlines()
    return code, err


def test_output_that_is_a_folder(tmp_path, video, capsys):
    folder = tmp_path / "out.bvh"
    folder.mkdir()
    code, err = _error(capsys, ["convert", video, "-o", folder])
    assert code == 2 and len(err) == 1
    assert err[0] == f"vidcap: error: {folder}: is a folder: give a file name to write"
    # the same for a second output of the command, and for other commands
    code, err = _error(capsys, ["convert", video, "-o", tmp_path / "a.bvh", "--save", folder])
    assert code == 2 and "is a folder" in err[0]
    code, err = _error(capsys, ["synth", "--frames", "3", "-o", folder])
    assert code == 2 and "is a folder" in err[0]
    assert list(folder.iterdir()) == [] and not (tmp_path / "a.bvh").exists()


def test_output_over_an_input_is_refused(video, capsys):
    before = video.read_bytes()
    code, err = _error(capsys, ["convert", video, "-o", video])
    assert code == 2 and err == [f"vidcap: error: {video}: -o is also an input of this command"
                                 " (the video): writing it would destroy it"]
    assert video.read_bytes() == before


def test_output_under_a_file(tmp_path, video, capsys):
    code, err = _error(capsys, ["pose2d", video, "-o", video / "sub" / "p.npz"])
    assert code == 2 and err[0].endswith(f"cannot write here: {video} is a file, not a folder")


def test_batch_outdir_that_is_a_file(video, capsys):
    code, err = _error(capsys, ["batch", video, "-o", video])
    assert code == 2 and err == [f"vidcap: error: {video}: is a file; OUTDIR must be a folder "
                                 "(created if missing)"]


def test_missing_folders_are_fine_and_atomic_path_checks_too(tmp_path):
    check_output_file(tmp_path / "new" / "deeper" / "x.bvh")  # created on writing
    with atomic_path(tmp_path / "new" / "x.txt") as tmp:
        tmp.write_text("ok")
    assert (tmp_path / "new" / "x.txt").read_text() == "ok"
    with pytest.raises(UsageError, match="is a folder"):
        with atomic_path(tmp_path / "new"):
            pass


@pytest.mark.parametrize("value", ["2", "-0.1"])
def test_keyframes_threshold_must_be_a_similarity(video, capsys, value):
    code, err = _error(capsys, ["convert", video, "-o", video.with_suffix(".bvh"),
                                "--keyframes", value])
    assert code == 2
    assert err == [f"vidcap: error: --keyframes is a fit similarity between 0 and 1, got "
                   f"{float(value)}"]


def test_a_bug_of_ours_is_one_line_not_a_traceback(tmp_path, video, capsys, monkeypatch):
    """An exception vidcap did not expect (a bug, not bad input) ends the command with one
    line and exit 1; `--debug` shows the traceback."""
    import vidcap.commands.convert as convert_command

    def broken(args):
        raise IndexError("index 46 is out of bounds for axis 0 with size 45")

    monkeypatch.setattr(convert_command, "run", broken)
    code, err = _error(capsys, ["convert", video, "-o", tmp_path / "o.bvh"])
    assert code == 1 and len(err) == 1, err
    assert err[0].startswith("vidcap: internal error: IndexError: index 46") and "--debug" in err[0]
    assert not (tmp_path / "o.bvh").exists()
    with pytest.raises(IndexError):
        main(["--debug", "convert", str(video), "-o", str(tmp_path / "o.bvh")])


def test_batch_hands_camera_and_ensemble_to_every_clip(tmp_path, video, capsys, monkeypatch):
    """``vidcap batch --camera 2.5,3 --ensemble 2``: every clip's conversion gets them, as
    ``vidcap convert`` would; a bad value is one line and exit 2 before any clip runs."""
    import vidcap.batch.local as local

    seen = []

    def fake_run_local(tasks, jobs):
        for task in tasks:
            seen.append(task.options)
            yield {"file": task.video, "output": task.output, "frames": 1, "seconds": 0.1,
                   "fps": 10.0, "status": "ok", "message": ""}

    monkeypatch.setattr(local, "run_local", fake_run_local)
    code = main(["batch", str(video), "-o", str(tmp_path / "out"), "--camera", "2.5,3",
                 "--ensemble", "2", "--seated"])
    assert code == 0 and len(seen) == 1
    assert seen[0]["camera"] == (2.5, 3.0) and seen[0]["ensemble"] == 2
    assert seen[0]["seated"] is True
    capsys.readouterr()
    code, err = _error(capsys, ["batch", video, "-o", tmp_path / "out2", "--camera", "2.5"])
    assert code == 2 and len(err) == 1 and err[0].startswith("vidcap: error: --camera")
    assert not (tmp_path / "out2").exists() and len(seen) == 1
