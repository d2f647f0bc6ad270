"""The collector is off while a stage sets up, and what it set up is frozen once."""

import gc

import pytest

from wipelab import long_lived
from wipelab.long_lived import long_lived_objects


@pytest.fixture
def fresh_process(monkeypatch):
    """As in a new process: nothing frozen yet (what earlier tests froze is let go)."""
    gc.unfreeze()
    monkeypatch.setattr(long_lived, "_frozen", False)
    yield
    gc.unfreeze()
    assert gc.isenabled()


def test_the_first_block_runs_without_collections_and_freezes_what_it_made(fresh_process):
    with long_lived_objects():
        assert not gc.isenabled()
        kept = [[index] for index in range(1000)]
    assert gc.isenabled()
    frozen = gc.get_freeze_count()
    assert frozen >= len(kept)
    with long_lived_objects():   # a later block: the collector runs, nothing more is frozen
        assert gc.isenabled()
        more = [[index] for index in range(1000)]
    assert gc.get_freeze_count() == frozen and len(more) == 1000


def test_a_block_that_fails_freezes_nothing(fresh_process):
    with pytest.raises(ValueError):
        with long_lived_objects():
            raise ValueError("no surface")
    assert gc.isenabled() and gc.get_freeze_count() == 0
    with long_lived_objects():   # the next one still does
        assert not gc.isenabled()
    assert gc.get_freeze_count() > 0
