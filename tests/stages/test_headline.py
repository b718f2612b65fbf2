"""The run's headline (capmap.stages.headline): only the families whose summaries exist, a table it
cannot read named instead of stopping the rest, and where the report is made."""

from __future__ import annotations

from capmap.stages.headline import headline


def test_only_present_families_and_a_broken_table_is_named(tmp_path):
    assert headline(tmp_path) == []  # nothing ran: nothing to say
    (tmp_path / "follow").mkdir()
    (tmp_path / "follow" / "summary.csv").write_text(
        "case,robot,follower_duration_s,toppra_duration_s,duration_ratio,follower_peak_torque_pct\n"
        "ground,ur5,0.913,0.857,1.0657,100.0001\n")
    (tmp_path / "dualarm").mkdir()
    (tmp_path / "dualarm" / "summary.csv").write_text("quantity,value\nconverged,True\n")  # no distances
    lines = headline(tmp_path)
    assert lines[0] == "following: ground (ur5) 0.913 s vs TOPP-RA 0.857 s (x1.066), peak torque 100.0 %"
    assert lines[1].startswith("dualarm/summary.csv: cannot be summarised")
    assert lines[2].endswith(f"snakemake --report {tmp_path}/report.zip") and len(lines) == 3


def test_a_path_that_cannot_be_followed_is_said_so_with_its_reason(tmp_path):
    (tmp_path / "follow").mkdir()
    (tmp_path / "follow" / "summary.csv").write_text(
        "case,robot,feasible,reason,follower_duration_s,toppra_duration_s,duration_ratio,follower_peak_torque_pct\n"
        "space,ssrms7,True,,70.073,59.25,1.1826,100.0\n"
        'ground,ur5,False,"tau_j1_nm: friction needs 4.00 N m, above its limit 0.01 N m",,,,\n')
    line = headline(tmp_path)[0]
    assert line == ("following: space (ssrms7) 70.1 s vs TOPP-RA 59.2 s (x1.183), peak torque 100.0 %; ground (ur5) "
                    "cannot be followed: tau_j1_nm: friction needs 4.00 N m, above its limit 0.01 N m")
    assert "nan" not in line
