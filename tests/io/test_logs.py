"""A job's console: one line when it finishes (its last message, wall time, memory), warnings at once, and a
long job's progress at most every CONSOLE_EVERY_S; its log file gets every line."""

import logging

from capmap.io import logs


def _job():
    log = logs.stage_logger("capmap.test", "shard 0 of 4")
    for i in range(100):
        log.info(f"{i + 1}/100 points")
    log.warning("a warning")
    log.info("done -> out.parquet")


def test_a_job_is_one_console_line_and_every_line_in_its_log(tmp_path, capfd):
    logs.call(_job, log=str(tmp_path / "job.log"))
    err = capfd.readouterr().err.splitlines()
    assert len(err) == 2 and err[0].endswith("shard 0 of 4: a warning")
    assert "shard 0 of 4: done -> out.parquet (" in err[1] and err[1].endswith(" MB)")
    text = (tmp_path / "job.log").read_text().splitlines()
    assert len(text) == 103 and "100/100 points" in text[99] and "job _job:" in text[-1]


def test_a_long_job_shows_its_progress(tmp_path, capfd, monkeypatch):
    monkeypatch.setattr(logs, "CONSOLE_EVERY_S", 0.0)  # every line is "30 s later"
    logs.call(_job, log=str(tmp_path / "job.log"))
    err = capfd.readouterr().err.splitlines()
    assert len(err) == 103 and "job _job" not in " ".join(err)  # 100 progress, warning, done, the job's line
    assert logging.getLogger("capmap").handlers == []  # the job's handlers are closed
