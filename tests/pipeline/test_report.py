"""``wipelab report``: the paper's figures and a summary from a run's real files."""

import json

import matplotlib.image
import numpy as np
import pytest
from click.testing import CliRunner

from wipelab.cli.pipeline_commands import report
from wipelab.errors import InputError
from wipelab.pipeline.report import write_report


@pytest.mark.slow
def test_report_draws_the_figures_of_every_stage_and_summarises_the_metrics(robot_run,
                                                                            tmp_path):
    _, run_dir = robot_run
    result = CliRunner().invoke(report, [str(run_dir), "-o", str(tmp_path / "report")])
    assert result.exit_code == 0, result.output
    written = sorted(p.name for p in (tmp_path / "report").iterdir())
    assert written == ["adapt_height_force.png", "adapt_profile.png", "learn_frequency.png",
                       "learn_waveform.png", "replay_force_error.png",
                       "replay_force_over_phase.png", "replay_height_force.png", "summary.md"]
    for name in written[:-1]:
        image = matplotlib.image.imread(tmp_path / "report" / name)
        assert image.shape[0] > 300 and image.shape[1] > 600, name
        assert image[..., :3].std() > 0.05, f"{name} is blank"
    summary = (tmp_path / "report" / "summary.md").read_text()
    model = json.loads((run_dir / "learn" / "model.json").read_text())
    assert summary.startswith("# Run run\n\n| stage | command | wall time (s) |")
    assert "| adapt | adapt |" in summary and "| replay | replay |" in summary
    key_metrics = summary.split("## Key metrics")[1].split("<details>")[0]
    assert f"| learn.frequency_hz | {model['frequency_hz']:.4g} |" in key_metrics
    assert "![learn: frequency adaptation" in summary


def test_report_of_a_directory_without_finished_stages(tmp_path):
    (tmp_path / "learn").mkdir()
    with pytest.raises(InputError, match="no finished stage"):
        write_report(tmp_path)
    assert not (tmp_path / "report").exists()


def test_learn_figures_shade_the_gaps_and_draw_no_bridge_over_them():
    from wipelab.pipeline.figures import frequency_figure, waveform_figure

    t = np.arange(0, 10, 1 / 30)
    observed = ~((t >= 4.0) & (t < 5.5))
    demonstrated = np.column_stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)])
    figure = waveform_figure(t, demonstrated, 0.9 * demonstrated, ["x", "y"], 1.0, observed)
    drawn = figure.axes[0].lines[0].get_ydata()
    assert np.isnan(drawn[~observed]).all() and not np.isnan(drawn[observed]).any()
    assert len(figure.axes[0].patches) == 1
    figure = frequency_figure(t, np.ones((t.size, 1)), ["omega"], observed=observed)
    assert "not observed" in [text.get_text() for text in figure.axes[0].get_legend().get_texts()]
