"""``wipelab report``: the paper's figures and a summary from a run's real files."""

import json

import matplotlib.colors
import matplotlib.image
import numpy as np
import pytest
from click.testing import CliRunner

from wipelab.cli import cli
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


def test_track_figure_draws_xyz_apart_against_the_truth_with_lost_frames_shaded():
    from wipelab.pipeline.figures import track_figure

    t = np.arange(0, 6, 1 / 30)
    truth = np.column_stack([0.6 + 0.08 * np.cos(t), 0.08 * np.sin(t), np.full(t.size, 0.9)])
    valid = ~((t > 2.0) & (t < 2.5))
    position = np.where(valid[:, None], truth + 0.002, np.nan)
    quality = ["box" if v else "" for v in valid]
    quality[100:110] = ["centroid"] * 10
    figure = track_figure(t, position, valid, truth, quality)
    assert [ax.get_ylabel() for ax in figure.axes[:4]] == ["x (m)", "y (m)", "z (m)", "error (mm)"]
    labels = [text.get_text() for text in figure.axes[0].get_legend().get_texts()]
    assert {"lost", "box fit failed: centroid", "truth", "tracked x"} <= set(labels)
    error = [text.get_text() for text in figure.axes[3].get_legend().get_texts()]
    assert error == ["lost", "box fit failed: centroid", "3D error, RMS 3.5 mm"]
    drawn = figure.axes[0].lines[0].get_ydata()
    assert np.isnan(drawn[~valid]).all()                 # a gap is a gap
    colours = {ax.lines[0].get_color() for ax in figure.axes[:3]}
    assert len(colours) == 3                              # x, y, z each its own colour


def test_a_single_frame_of_a_quality_is_shaded_as_wide_as_a_frame():
    from wipelab.pipeline.figures import track_figure

    t = np.arange(0, 2, 1 / 30)
    position = np.column_stack([np.cos(t), np.sin(t), np.full(t.size, 0.9)])
    quality = ["box"] * t.size
    quality[30] = "centroid"
    figure = track_figure(t, position, np.ones(t.size, bool), quality=quality)
    (span,) = figure.axes[0].patches
    assert np.isclose(span.get_width(), 1 / 30)
    assert np.isclose(span.get_x() + 0.5 * span.get_width(), t[30])


def test_the_quality_column_is_read_when_track_csv_has_one(tmp_path):
    from wipelab.pipeline.report import _quality

    path = tmp_path / "track.csv"
    path.write_text("t,x,y,z,valid,quality\n0,1,2,3,1,box\n0.1,,,,0,\n0.2,1,2,3,1,centroid\n")
    assert _quality(path) == ["box", "", "centroid"]
    path.write_text("t,x,y,z,valid\n0,1,2,3,1\n")
    assert _quality(path) is None


def test_replay_figures_name_modes_and_speeds_with_their_frequency():
    from wipelab.logs.palette import MODE_COLOURS, hex_colour, speed_colours
    from wipelab.pipeline.figures import force_error_bars_figure, force_over_phase_figure

    phase = np.linspace(0, 2 * np.pi, 65)
    colours = speed_colours([1.0, 2.0])
    curves = {mode: [("1x (0.25 Hz)", colours[1.0], phase, 10 + np.sin(phase)),
                     ("2x (0.50 Hz)", colours[2.0], phase, 10 + 2 * np.sin(phase))]
              for mode in ("learned", "planar")}
    figure = force_over_phase_figure(curves, 10.0, "replay")
    panels = [ax for ax in figure.axes if ax.get_visible()]
    assert [ax.get_title(loc="left") for ax in panels] == ["learned", "planar"]
    assert [line.get_label() for line in panels[0].lines] == ["1x (0.25 Hz)", "2x (0.50 Hz)",
                                                               "F0 = 10 N"]
    assert panels[0].lines[0].get_color() != panels[0].lines[1].get_color()
    bars = force_error_bars_figure({"1x (0.25 Hz)": {"planar": 9.0, "learned": 1.0}}, "e")
    ax = bars.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["1x (0.25 Hz)"]
    assert ax.patches[0].get_facecolor()[:3] == pytest.approx(
        matplotlib.colors.to_rgb(hex_colour(MODE_COLOURS["learned"])))


@pytest.mark.slow
def test_report_of_a_tracked_synthetic_demo_draws_the_track_against_its_truth(tmp_path):
    from wipelab.pipeline.runner import run_pipeline
    from wipelab.pipeline.spec import load_pipeline

    assert CliRunner().invoke(cli, ["synth", str(tmp_path / "demo"), "--pattern", "line",
                                    "--frequency", "1.5", "--duration", "2",
                                    "-q"]).exit_code == 0
    (tmp_path / "p.toml").write_text('[pipeline]\nname = "t"\n[inputs]\ndemo = "demo"\n'
                                     '[stages.track]\ninput = "demo"\nparticles = 60\n')
    run_pipeline(load_pipeline(tmp_path / "p.toml"), tmp_path / "run", quiet=True)
    out = write_report(tmp_path / "run")
    summary = (out / "summary.md").read_text()
    assert "![track: the tracked sponge centre" in summary and "truth.csv" in summary
    image = matplotlib.image.imread(out / "track_trajectory.png")
    assert image.shape[0] > 600 and image[..., :3].std() > 0.05
