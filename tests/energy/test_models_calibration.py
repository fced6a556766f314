"""Tests of energy.models.calibration: fit_interval gives any model a cross-validated forecast interval."""

import dataclasses

import numpy as np
import pytest
from interval_samples import interval_log

from energy import load_current_model
from energy.models import LinearCurrentModel, fit_interval
from terrawatt_base.errors import DataError, InvalidParameterError


def test_fit_interval_gives_any_model_a_cross_validated_interval(tmp_path):
    logs = [interval_log(s, "a", offset_a=0.3 * (s % 3)) for s in range(6)] + [interval_log(20 + s, "b", gain=1.3) for s in range(6)]
    lin = fit_interval(LinearCurrentModel(), logs, folds=3)
    assert lin.gives_interval and lin.interval_.cross_validated and lin.interval_.new_ground_cov is not None
    known = lin.predict_distribution(logs[0]).charge()
    assert known.total_sd_as > 0
    np.testing.assert_allclose(lin.predict_distribution(logs[0]).mean_a, lin.predict(logs[0]))
    unseen = dataclasses.replace(logs[0], meta=dataclasses.replace(logs[0].meta, ground_label="c"))
    assert lin.predict_distribution(unseen).charge().total_sd_as > known.total_sd_as
    back = load_current_model(lin.save(tmp_path / "lin.zip"))
    assert back.gives_interval
    assert back.predict_distribution(logs[0]).charge().total_sd_as == pytest.approx(known.total_sd_as)
    adapted = back.adapt(logs[1].slice(0.0, 20.0), method="bayes")
    again = load_current_model(adapted.save(tmp_path / "adapted.zip"))  # the base's interval travels with it
    assert again.gives_interval
    np.testing.assert_allclose(again.predict_distribution(logs[2]).run_sd_a, adapted.predict_distribution(logs[2]).run_sd_a)
    with pytest.raises(DataError, match="at least 2"):
        fit_interval(LinearCurrentModel(), logs[:1])
    with pytest.raises(InvalidParameterError):
        fit_interval(adapted, logs)


def _fitted(tmp_path):
    logs = [interval_log(s, "a", offset_a=0.3 * (s % 3)) for s in range(4)] + [interval_log(20 + s, "b", gain=1.3) for s in range(4)]
    return fit_interval(LinearCurrentModel(), logs, folds=2), logs


@pytest.mark.parametrize(("tamper", "message"), [
    (lambda c: -c, "negative variance"),  # negated: would narrow the interval it should widen
    (lambda c: c - 2.0 * np.diag(np.diag(c[0]))[None], "negative variance"),
    (lambda c: c * 1e30, "beyond any plausible spread"),  # would print negative energies
    (lambda c: c + np.triu(np.ones_like(c[0]), 1)[None], "not symmetric"),
])
def test_a_model_file_whose_interval_means_nothing_is_refused(tmp_path, tamper, message):
    from terrawatt_base.errors import FileFormatError

    lin, _ = _fitted(tmp_path)
    iv = lin.interval_
    lin.interval_ = dataclasses.replace(iv, run_cov={g: tamper(c) for g, c in iv.run_cov.items()})
    path = lin.save(tmp_path / "bad.zip")
    with pytest.raises(FileFormatError, match=message):
        load_current_model(path)
    lin.interval_ = dataclasses.replace(iv, new_ground_cov=tamper(iv.new_ground_cov))
    with pytest.raises(FileFormatError, match=message):
        load_current_model(lin.save(tmp_path / "bad_new.zip"))
    lin.interval_ = dataclasses.replace(iv, sample_sd_a=iv.sample_sd_a * 1e30)
    with pytest.raises(FileFormatError, match="plausible spread"):
        load_current_model(lin.save(tmp_path / "bad_sd.zip"))


def test_an_adapted_model_whose_posterior_is_not_a_covariance_is_refused(tmp_path):
    from terrawatt_base.errors import FileFormatError

    lin, logs = _fitted(tmp_path)
    adapted = lin.adapt(logs[1].slice(0.0, 20.0), method="bayes")
    assert load_current_model(adapted.save(tmp_path / "ok.zip")).gives_interval
    adapted.posterior_cov_ = -adapted.posterior_cov_
    with pytest.raises(FileFormatError, match="posterior_cov.*negative variance"):
        load_current_model(adapted.save(tmp_path / "neg.zip"))


@pytest.mark.parametrize("block", ["interval", "trained_on"])
def test_a_model_file_whose_interval_or_training_block_is_not_a_mapping_is_refused(tmp_path, block):
    """Dropping such a block would load a model without its interval (or training record) without a word."""
    import json
    import zipfile

    from terrawatt_base.errors import FileFormatError

    lin, _ = _fitted(tmp_path)
    path = lin.save(tmp_path / "m.zip")
    with zipfile.ZipFile(path) as z:
        entries = {i.filename: z.read(i.filename) for i in z.infolist()}
    name = next(n for n in entries if n.endswith(".json"))
    doc = json.loads(entries[name])
    assert block in doc, sorted(doc)
    doc[block] = "not a mapping"
    entries[name] = json.dumps(doc).encode()
    with zipfile.ZipFile(tmp_path / "bad.zip", "w") as z:
        for n, data in entries.items():
            z.writestr(n, data)
    with pytest.raises(FileFormatError, match=f"the '{block}' entry must be a mapping or absent, got str"):
        load_current_model(tmp_path / "bad.zip")
