import numpy as np
import pytest


def pytest_configure(config):
    """Each test process runs BLAS on one thread, as ``alpes-dyn`` does (:mod:`alpes_dyn.blas_threads`): two
    workers on two cores, each with spinning BLAS threads, would take the cores from each other."""
    from alpes_dyn.blas_threads import one_blas_thread

    one_blas_thread()


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture
def cli_text(monkeypatch):
    """The tables the commands run in the test would print without ``--json``, in order: every ``_emit`` of
    ``alpes_dyn.cli`` is given the JSON object and the table together, so one run (a ``--json`` one) checks both
    (a command's second run without ``--json`` would redo its fit or its EKF for the table alone)."""
    import sys

    from alpes_dyn.cli import common

    texts: list[str] = []
    emit = common._emit

    def both(obj, text, as_json):
        texts.append(text)
        emit(obj, text, as_json)

    monkeypatch.setattr(common, "_emit", both)  # the modules imported from here on bind this one
    for name, module in list(sys.modules.items()):
        if name.startswith("alpes_dyn.cli") and getattr(module, "_emit", None) is emit:
            monkeypatch.setattr(module, "_emit", both)
    return texts
