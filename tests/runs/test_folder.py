"""Reading run folders: status lines and params files of runs of this version and of
rvmsim 0.1 (settings in run.json, free-text status), and refusals that say what to do."""

from __future__ import annotations

import json

import pytest

from rvmsim.errors import RvmsimError
from rvmsim.tune import resume
from rvmsim.runs import diverse_candidates, find_runs, is_run_folder, rank_params_text, status_lines

from ..cli_runner import run_in_process
from ..tune.common import make_legacy_run


def test_status_and_params_file_of_a_run(clean, tmp_path):
    from rvmsim.isp import load_params
    from rvmsim.runs import RunStore

    # the plain score order (--by-score), as status and select offered it before the
    # diverse top-M
    lines = status_lines(clean, 2, by_score=True)
    assert lines[0] == f"{clean}: done, strategy random, 60 / 60 evaluations"
    assert lines[1] == "  the 2 best trials by EC score (--by-score)"
    assert len(lines) == 4 and lines[2].startswith("  #1  EC score ")
    store = RunStore(clean / "run.sqlite")
    second = store.top(2)[1]
    store.close()
    assert f"trial {second.idx:>6} (random)" in lines[3]
    text = rank_params_text(clean, 2, by_score=True)
    assert text.startswith(f"# rank 2: EC score {second.score:.6g} (trial {second.idx}, random)")
    (tmp_path / "p.yaml").write_text(text)
    params, out = load_params(tmp_path / "p.yaml")
    assert params == second.params and (out.width, out.height) == (160, 90)
    with pytest.raises(RvmsimError, match="only 60 candidates, no rank 61"):
        rank_params_text(clean, 61, by_score=True)
    # the default: rank K of the diverse top-M
    diverse = diverse_candidates(clean, 2)
    lines = status_lines(clean, 2)
    # the list is named, and its columns explained, before it
    assert lines[1].startswith("  the diverse top-2, not in score order: #1 is the best")
    assert "at least 0.05 of each tuned parameter's search span" in lines[1]
    assert lines[2].startswith("  (distance: to #1")
    assert len(lines) == 5 and f"trial {diverse[1].trial:>6} (random)" in lines[4]
    assert f"(distance {diverse[1].distance:.2f}: {diverse[1].differs})" in lines[4]
    text = rank_params_text(clean, 2)
    assert text.startswith(f"# rank 2: EC score {diverse[1].score:.6g} (trial "
                           f"{diverse[1].trial}, random)\n# differs from rank 1: ")
    (tmp_path / "p.yaml").write_text(text)
    assert load_params(tmp_path / "p.yaml")[0] == diverse[1].params
    with pytest.raises(RvmsimError, match=r"only \d+ candidates at least 0.05 apart .*, no "
                                          "rank 61"):
        rank_params_text(clean, 61)
    assert is_run_folder(clean) and find_runs(clean.parent) == [clean]
    assert not is_run_folder(tmp_path) and find_runs(tmp_path / "nothing") == []


def test_old_run_folders_are_read_by_status_select_and_report(clean, tmp_path):
    from rvmsim.report import write_report

    old = make_legacy_run(clean, tmp_path / "old")
    assert status_lines(old) == [ln.replace(str(clean), str(old)) for ln in status_lines(clean)]
    assert "done, strategy random, 60 / 60 evaluations" in status_lines(old)[0]
    assert rank_params_text(old, 2) == rank_params_text(clean, 2)
    assert "Vehicle A" in write_report(old).read_text(encoding="utf-8")
    # the CLI reads it too
    st = run_in_process(["status", old, "--top", "2"])
    assert st.code == 0 and st.stdout.splitlines() == status_lines(old, 2)
    # the report follows the scene path run.json records (as it always did)
    info = json.loads((old / "run.json").read_text())
    info["scene"] = str(tmp_path / "gone.yaml")
    (old / "run.json").write_text(json.dumps(info))
    with pytest.raises(RvmsimError, match="gone.yaml"):
        write_report(old)


def test_old_runs_that_cannot_be_read_are_refused_with_what_to_do(clean, tmp_path):
    from rvmsim.report import write_report

    bare = make_legacy_run(clean, tmp_path / "bare", run_json=False)
    assert "done, strategy random, 60 / 60" in status_lines(bare)[0]  # the store suffices
    for call in (lambda: rank_params_text(bare), lambda: resume(bare),
                 lambda: write_report(bare)):
        with pytest.raises(RvmsimError) as err:
            call()
        msg = str(err.value)
        assert "\n" not in msg and str(bare) in msg
        assert "restore run.json, or start a new run" in msg
    broken = make_legacy_run(clean, tmp_path / "broken")
    (broken / "run.json").write_text("{not json")
    with pytest.raises(RvmsimError, match=r"run\.json: not a readable run\.json .*start a new "
                                          "run") as err:
        resume(broken)
    assert "\n" not in str(err.value)
    sel = run_in_process(["select", bare])
    assert sel.code == 2 and len(sel.stderr.strip().splitlines()) == 1
    assert "start a new run" in sel.stderr and "Traceback" not in sel.stderr
