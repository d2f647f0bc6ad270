"""Pipeline files: parsing, references between stages, overrides, and the errors users see."""

from pathlib import Path

import pytest

from wipelab.errors import InputError
from wipelab.pipeline.spec import load_pipeline

PIPELINE = """
[pipeline]
name = "example"

[inputs]
demo = "demos/one"

[stages.track]
input = "demo"
seed = 3

[stages.learn]
input = "track:track.csv"
dofs = ["x", "y"]

[stages.fast]
command = "rollout"
input = "learn:model.json"
periods = 2
"""


def write(tmp_path: Path, text: str, name: str = "p.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_stages_keep_file_order_commands_default_to_names_and_inputs_resolve(tmp_path):
    pipeline = load_pipeline(write(tmp_path, PIPELINE))
    assert [s.name for s in pipeline.stages] == ["track", "learn", "fast"]
    assert [s.command for s in pipeline.stages] == ["track", "learn", "rollout"]
    assert pipeline.stage("fast").output == "rollout.csv"
    assert pipeline.stage("learn").parameters == {"dofs": ["x", "y"]}
    run = Path("/runs/r")
    assert pipeline.resolve_input(pipeline.stage("track"), run) == tmp_path / "demos" / "one"
    assert pipeline.resolve_input(pipeline.stage("learn"), run) == run / "track" / "track.csv"
    assert pipeline.upstream(pipeline.stage("fast")) == "learn"
    assert pipeline.upstream(pipeline.stage("track")) is None


def test_a_file_inside_a_named_input(tmp_path):
    pipeline = load_pipeline(write(tmp_path, PIPELINE)).with_overrides(
        sets=["learn.input=demo:truth.csv"])
    stage = pipeline.stage("learn")
    assert pipeline.resolve_input(stage, tmp_path / "run") == tmp_path / "demos/one/truth.csv"
    assert pipeline.upstream(stage) is None


def test_a_plain_input_path_is_relative_to_the_pipeline_file(tmp_path):
    pipeline = load_pipeline(write(tmp_path, '[stages.learn]\ninput = "data/traj.csv"\n'))
    stage = pipeline.stage("learn")
    assert pipeline.resolve_input(stage, tmp_path / "run") == tmp_path / "data" / "traj.csv"


def test_overrides_parse_toml_values_and_fall_back_to_strings(tmp_path):
    pipeline = load_pipeline(write(tmp_path, PIPELINE)).with_overrides(
        sets=["learn.kernels=30", "fast.frequency = 2.5", "track.color=red",
              "learn.dofs=[\"x\"]", "fast.input=learn:other.json"],
        inputs=[str(tmp_path / "elsewhere")])
    assert pipeline.stage("learn").parameters == {"dofs": ["x"], "kernels": 30}
    assert pipeline.stage("fast").parameters["frequency"] == 2.5
    assert pipeline.stage("track").parameters == {"seed": 3, "color": "red"}
    assert pipeline.stage("fast").input == "learn:other.json"
    assert pipeline.inputs["demo"] == tmp_path / "elsewhere"


@pytest.mark.parametrize("text, message", [
    ("[stages.learn\n", "not valid TOML"),
    ("[stagez.learn]\n", "unknown table(s) stagez"),
    ("[pipeline]\nname = 'x'\n", "no stages"),
    ("[stages.fly]\ninput = 'a.csv'\n", "stage fly: unknown command 'fly'"),
    ("[stages.learn]\nkernels = 3\n", "stage learn: learn needs input"),
    ("[stages.synth]\ninput = 'x'\n", "stage synth: synth takes no input"),
    ("[stages.learn]\ninput = 'track:track.csv'\n", "names no stage ('track')"),
    ("[stages.learn]\ninput = 'later:model.json'\n[stages.later]\ncommand = 'synth'\n",
     "names a later stage ('later')"),
    ("[stages.learn]\ninput = 'a.csv'\noutput = 'x.csv'\n", "output must be a plain file name"),
    ("[stages.learn]\ninput = 'a.csv'\nquiet = true\n", "'quiet' is set by the pipeline runner"),
    ("[stages.learn]\ninput = 'a.csv'\nkernels = {n = 3}\n", "kernels must be a string"),
    ("[stages.'bad name']\ncommand = 'synth'\n", "bad stage name 'bad name'"),
    ("[stages.report]\ncommand = 'synth'\n", "stage 'report': name taken"),
])
def test_bad_pipeline_files_are_named_with_what_is_wrong(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(InputError, match=r"^" + str(path).replace(".", r"\.") + ": .*") as info:
        load_pipeline(path)
    assert message in str(info.value)


def test_missing_pipeline_file(tmp_path):
    with pytest.raises(InputError, match=r"nope\.toml: file not found"):
        load_pipeline(tmp_path / "nope.toml")


@pytest.mark.parametrize("sets, inputs, message", [
    (["learn.kernels"], [], "--set learn.kernels: expected STAGE.KEY=VALUE"),
    (["kernels=3"], [], "--set kernels=3: expected STAGE.KEY=VALUE"),
    (["lern.kernels=3"], [], "no stage named 'lern' (stages: track, learn, fast)"),
    (["learn.command=adapt"], [], "a stage's command cannot be overridden"),
    (["learn.input=fast:rollout.csv"], [], "names a later stage ('fast')"),
    ([], ["video=/tmp"], "the pipeline has no input 'video' (inputs: demo)"),
])
def test_bad_overrides(tmp_path, sets, inputs, message):
    pipeline = load_pipeline(write(tmp_path, PIPELINE))
    with pytest.raises(InputError) as info:
        pipeline.with_overrides(sets=sets, inputs=inputs)
    assert message in str(info.value)


def test_file_parameters_resolve_against_the_pipeline_file_or_the_current_directory(
        tmp_path, monkeypatch):
    text = PIPELINE + 'surface = { file = "surfaces/wavy.toml" }\n'
    pipeline = load_pipeline(write(tmp_path, text))
    assert pipeline.stage("fast").parameters["surface"] == {
        "file": str(tmp_path / "surfaces" / "wavy.toml")}
    (tmp_path / "demos").mkdir()
    monkeypatch.chdir(tmp_path / "demos")
    overridden = pipeline.with_overrides(sets=['fast.surface={file = "mine.toml"}'])
    assert overridden.stage("fast").parameters["surface"] == {
        "file": str(tmp_path / "demos" / "mine.toml")}
