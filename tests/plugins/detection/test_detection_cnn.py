"""The small CNN: every layer's gradient against finite differences, the Network port type,
training, divergence, and cnn_digits.yaml against the issue's accuracy."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins import cnn
from graphvision_plugins.recognition._types import SampleSet

from ...conftest import PIPELINES


def _relative_error(analytic: np.ndarray, numeric: np.ndarray) -> float:
    return float(np.abs(analytic - numeric).max() / max(np.abs(numeric).max(), 1e-12))


def _numeric_gradient(f, x: np.ndarray, step: float = 1e-6) -> np.ndarray:
    """Central differences of the scalar f at x (x changed in place and restored)."""
    grad = np.zeros_like(x)
    flat, out = x.reshape(-1), grad.reshape(-1)
    for i in range(flat.size):
        keep = flat[i]
        flat[i] = keep + step
        up = f()
        flat[i] = keep - step
        down = f()
        flat[i] = keep
        out[i] = (up - down) / (2 * step)
    return grad


@pytest.mark.parametrize(
    ("text", "shape"),
    [
        ("conv 3x3", (2, 5, 6)),
        ("conv 2x3 pad 0", (3, 5, 5)),
        ("conv 2x2 pad 2", (1, 4, 3)),
        ("relu", (2, 4, 4)),
        ("maxpool 2", (2, 5, 6)),  # an odd side: the last row is dropped
        ("maxpool 3", (1, 6, 6)),
        ("dense 4", (2, 3, 3)),
        ("dense 3", (7,)),
    ],
)
def test_each_layer_gradient_equals_finite_differences(text, shape):
    rng = np.random.default_rng(0)
    layer = cnn.parse_layer(text)
    x = rng.normal(size=(3, *shape))
    params = [rng.normal(size=s) for s in layer.parameter_shapes(shape)]
    out_shape = layer.output_shape(shape)
    probe = rng.normal(size=(3, *out_shape))  # the loss sum(probe · y) has dL/dy = probe

    def loss() -> float:
        return float((layer.forward(x, params)[0] * probe).sum())

    y, saved = layer.forward(x, params)
    assert y.shape == (3, *out_shape)
    d_x, d_params = layer.backward(probe, saved, params)
    assert _relative_error(d_x, _numeric_gradient(loss, x)) < 1e-4
    for analytic, param in zip(d_params, params, strict=True):
        assert _relative_error(analytic, _numeric_gradient(loss, param)) < 1e-4


def test_softmax_cross_entropy_gradient_and_value():
    rng = np.random.default_rng(1)
    scores = rng.normal(size=(5, 4))
    targets = np.array([0, 3, 1, 1, 2])
    loss, grad = cnn.softmax_cross_entropy(scores, targets)
    p = np.exp(scores) / np.exp(scores).sum(axis=1, keepdims=True)
    assert loss == pytest.approx(-np.log(p[np.arange(5), targets]).mean(), rel=1e-12)
    numeric = _numeric_gradient(lambda: cnn.softmax_cross_entropy(scores, targets)[0], scores)
    assert _relative_error(grad, numeric) < 1e-4


def test_whole_network_gradient_equals_finite_differences():
    rng = np.random.default_rng(2)
    layers = ["conv 2x3", "relu", "maxpool 2", "conv 3x3 pad 0", "relu", "dense 3"]
    architecture = cnn.build_architecture((1, 8, 8), layers)
    weights = cnn.initial_weights(architecture, seed=3)
    x, targets = rng.normal(size=(4, 1, 8, 8)), np.array([0, 2, 1, 2])

    def loss() -> float:
        return cnn.softmax_cross_entropy(architecture.forward(weights, x)[0], targets)[0]

    scores, saved = architecture.forward(weights, x, keep=True)
    grad = architecture.backward(weights, cnn.softmax_cross_entropy(scores, targets)[1], saved)
    assert _relative_error(grad, _numeric_gradient(loss, weights)) < 1e-4


def test_conv_equals_a_direct_correlation():
    rng = np.random.default_rng(4)
    layer = cnn.parse_layer("conv 2x3 pad 0")
    x = rng.normal(size=(1, 1, 5, 5))
    weights, bias = rng.normal(size=(2, 1, 3, 3)), np.array([0.5, -1.0])
    y = layer.forward(x, [weights, bias])[0]
    for f in range(2):
        for r in range(3):
            for c in range(3):
                direct = (x[0, 0, r : r + 3, c : c + 3] * weights[f, 0]).sum() + bias[f]
                assert y[0, f, r, c] == pytest.approx(direct, abs=1e-12)


# --- the Network port type -------------------------------------------------------------


def test_layers_that_do_not_chain_are_refused_naming_the_layer():
    layers = ["conv 4x3", "maxpool 2", "maxpool 2", "conv 4x5 pad 0", "dense 10"]
    with pytest.raises(ValueError, match=r"layer 3 'conv 4x5 pad 0' does not chain: its 5×5"):
        cnn.build_architecture((1, 8, 8), layers)
    with pytest.raises(ValueError, match=r"layer 2 'maxpool 2' does not chain: .*vector"):
        cnn.build_architecture((1, 8, 8), ["dense 5", "relu", "maxpool 2"])
    with pytest.raises(ValueError, match=r"layer 1 'conv3x3' does not chain: 'conv3x3' is not"):
        cnn.build_architecture((1, 8, 8), ["relu", "conv3x3"])


def test_training_refuses_a_last_layer_of_the_wrong_width():
    samples = SampleSet(np.zeros((4, 8, 8), np.float32), np.array([0, 1, 2, 1]))
    with pytest.raises(ValueError, match=r"layer 0 'dense 10' gives \(10,\) outputs but the "):
        cnn.train(samples, layers=["dense 10"])


def test_network_port_checks_weights_and_round_trips():
    architecture = cnn.build_architecture((1, 4, 4), ["conv 2x3", "relu", "dense 3"])
    weights = cnn.initial_weights(architecture, 0)
    spec = '{"input": [1, 4, 4], "layers": ["conv 2x3", "relu", "dense 3"]}'
    network = cnn.NetworkModel(spec, weights, np.array([0, 1, 2]), np.zeros(0))
    back = cnn.NetworkPort.decode(*cnn.NetworkPort.encode(cnn.NetworkPort.validate(network)))
    images = np.random.default_rng(0).random((2, 4, 4))
    np.testing.assert_array_equal(back.scores(images), network.scores(images))
    bad = weights.copy()
    bad[3] = np.nan
    with pytest.raises(gv.PortValueError, match="'weights' must be finite"):
        cnn.NetworkPort.validate(cnn.NetworkModel(spec, bad, np.array([0, 1, 2]), np.zeros(0)))
    with pytest.raises(gv.PortValueError, match=r"must hold \d+ values"):
        cnn.NetworkPort.validate(cnn.NetworkModel(spec, weights[:-1], np.arange(3), np.zeros(0)))
    broken = spec.replace("conv 2x3", "conv 2x7 pad 0")
    with pytest.raises(gv.PortValueError, match="layer 0 'conv 2x7 pad 0' does not chain"):
        cnn.NetworkPort.validate(cnn.NetworkModel(broken, weights, np.arange(3), np.zeros(0)))


# --- training ------------------------------------------------------------------------


@pytest.fixture(scope="module")
def digits():
    return cnn.digits()


def test_digits_split_is_seeded_80_20_and_stratified(digits):
    assert len(digits.train) + len(digits.test) == 1797  # scikit-learn's digits
    assert len(digits.test) == pytest.approx(0.2 * 1797, abs=5)
    assert np.bincount(digits.test.labels).min() >= 35  # every class held out
    again = cnn.digits()
    np.testing.assert_array_equal(again.test.labels, digits.test.labels)


def test_a_diverging_learning_rate_stops_with_a_message(digits):
    with pytest.raises(ValueError, match=r"cnn\.train: the loss diverged .* learning_rate=50;"):
        cnn.train(digits.train, layers=["dense 10"], learning_rate=50.0, epochs=3)


def test_a_network_that_learned_nothing_is_refused(digits):
    """At learning rate 0.5 the ReLUs die: the loss stays at log 10 without diverging
    (history 2.24, 2.35, 2.36 on this split)."""
    with pytest.raises(ValueError, match=r"cnn\.train: the network learned nothing: after 3"):
        cnn.train(digits.train, epochs=3, learning_rate=0.5)


def test_divergence_in_a_pipeline_names_the_node_and_caches_nothing(tmp_path):
    cache = gv.Cache(disk=gv.DiskStore(tmp_path))
    with pytest.raises(
        gv.RunError, match=r"node 'linear' \(op cnn.train\) failed.*learning_rate=80"
    ):
        gv.run(
            gv.load_pipeline(PIPELINES / "cnn_digits.yaml"),
            cache=cache,
            outputs=["linear_accuracy"],
            overrides={"linear.learning_rate": 80.0},
        )
    stored = {path.name for path in tmp_path.rglob("*.gvc")}
    assert len(stored) == 2  # split.train and split.test alone: no network was written


def test_missing_scikit_learn_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "sklearn.datasets", None)
    with pytest.raises(ImportError, match="pip install scikit-learn"):
        cnn.digits()


def test_cnn_digits_pipeline_meets_the_issue_accuracy(tmp_path):
    """The issue's truth: the CNN reaches 0.97 on the held-out 20 %; softmax regression
    (a linear classifier) stays below it (about 0.95, the issue says)."""
    cache = gv.Cache(disk=gv.DiskStore(tmp_path))
    graph = gv.load_pipeline(PIPELINES / "cnn_digits.yaml")
    out = gv.run(graph, cache=cache).outputs
    assert out["accuracy"] >= 0.97
    assert 0.9 < out["linear_accuracy"] < out["accuracy"]
    assert out["network"].history[-1] < out["network"].history[0] / 10
    table = out["predictions"]
    assert np.mean(table["predicted"] == table["label"]) == out["accuracy"]
    again = gv.run(graph, cache=gv.Cache(disk=gv.DiskStore(tmp_path)), outputs=["network"])
    assert {n.name: n.status for n in again.record.nodes}["cnn"] == "cached"
    np.testing.assert_array_equal(again.outputs["network"].weights, out["network"].weights)
    again = gv.run(graph, cache=gv.Cache(disk=gv.DiskStore(tmp_path)), outputs=["accuracy"])
    assert again.outputs["accuracy"] == out["accuracy"]


def test_a_network_crosses_process_boundaries():
    graph = gv.load_pipeline(PIPELINES / "cnn_digits.yaml")
    short = {"cnn.epochs": 1, "linear.epochs": 1}
    here = gv.run(graph, executor="sync", overrides=short, outputs=["network", "accuracy"])
    there = gv.run(
        graph, executor="processes", workers=2, overrides=short, outputs=["network", "accuracy"]
    )
    np.testing.assert_array_equal(there.outputs["network"].weights, here.outputs["network"].weights)
    assert there.outputs["accuracy"] == here.outputs["accuracy"]


def test_network_preview_shows_the_first_filters():
    architecture = cnn.build_architecture((1, 8, 8), ["conv 4x3", "relu", "dense 2"])
    spec = '{"input": [1, 8, 8], "layers": ["conv 4x3", "relu", "dense 2"]}'
    weights = cnn.initial_weights(architecture, 0)
    network = cnn.NetworkModel(spec, weights, np.arange(2), np.zeros(0))
    picture = cnn.NetworkPort.preview(network)
    assert picture is not None and picture.shape == (30, 4 * 31 - 1)  # 4 filters drawn 30×30
    assert picture.min() == 0 and picture.max() == 1


def test_layers_that_do_not_chain_in_a_pipeline_name_the_node_and_the_layer():
    layers = ["conv 8x3", "maxpool 2", "maxpool 2", "maxpool 2", "maxpool 2", "dense 10"]
    message = r"node 'cnn' \(op cnn.train\) failed.*layer 4 'maxpool 2' does not chain"
    with pytest.raises(gv.RunError, match=message):
        gv.run(
            gv.load_pipeline(PIPELINES / "cnn_digits.yaml"),
            outputs=["accuracy"],
            overrides={"cnn.layers": layers},
        )


@pytest.mark.parametrize(
    ("layers", "message"),
    [
        (["conv 8x3", "relu", "blah 3"], r"layers\[2\]: 'blah 3' is not a layer; write 'conv FxK'"),
        (["conv 0x3", "dense 10"], r"layers\[0\]: 'conv 0x3': sizes and counts must be at least 1"),
        ([], r"layers is empty"),
    ],
)
def test_a_layer_that_is_not_one_is_refused_before_the_run(layers, message):
    graph = gv.load_pipeline(PIPELINES / "cnn_digits.yaml")
    with pytest.raises(gv.PipelineError, match=r"--set cnn\.layers=.*: cnn\.train: " + message):
        gv.run(graph, outputs=["accuracy"], overrides={"cnn.layers": layers}, cache=None)


def test_a_misspelt_layer_in_a_file_is_named_with_its_line(tmp_path):
    text = (
        (PIPELINES / "cnn_digits.yaml")
        .read_text()
        .replace('"maxpool 2", "conv', '"maxpol 2", "conv')
    )
    path = tmp_path / "typo.yaml"
    path.write_text(text)
    line = next(n for n, row in enumerate(text.splitlines(), 1) if "maxpol" in row)
    with pytest.raises(
        gv.PipelineError,
        match=rf"nodes.cnn.params at .*typo.yaml:{line}: cnn.train: layers\[2\]: 'maxpol 2' is not",
    ):
        gv.compile_graph(gv.load_pipeline(path), gv.discover())
