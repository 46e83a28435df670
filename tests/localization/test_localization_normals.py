"""The keyed normals of `_kernels.normals` against NumPy's: the same bits."""

import numpy as np
import pytest

from robotlib.localization._kernels import normals


@pytest.fixture(scope="module")
def corridor():
    from robotlib.world import load_world

    return load_world("corridor")


def _numpy_state(key, chunk):
    bg = np.random.SFC64(np.random.SeedSequence([key, chunk]))
    return np.array(bg.state["state"]["state"], dtype=np.uint64)


@pytest.mark.parametrize(
    "key", [0, 1, 7, 2**32 - 1, 2**32, 2**32 + 5, 123456789012345, 2**63 - 1]
)
@pytest.mark.parametrize("chunk", [0, 1, 2, 121, 2**31])
def test_sfc64_state_is_numpys(key, chunk):
    s = np.empty(4, dtype=np.uint64)
    normals.sfc64_state(key, chunk, s)
    np.testing.assert_array_equal(s, _numpy_state(key, chunk))


def test_fill_chunk_is_numpys_generator():
    rng = np.random.default_rng(3)
    for key in [*rng.integers(np.iinfo(np.int64).max, size=20), 0, 2**63 - 1]:
        key, chunk = int(key), int(rng.integers(0, 200))
        # enough rows that the ziggurat's rare branches (tail, wedges) run
        got = np.empty((8192, 3))
        normals.fill_chunk(key, chunk, got)
        gen = np.random.Generator(np.random.SFC64(np.random.SeedSequence([key, chunk])))
        np.testing.assert_array_equal(got, gen.standard_normal((8192, 3)))


@pytest.mark.parametrize("n", [1, 8191, 8192, 8193, 30_000])
def test_fill_chunks_is_standard_normals(n):
    from robotlib.localization.motion import NORMALS_CHUNK

    key = 987654321987
    ref = np.empty((n, 3))
    for c, lo in enumerate(range(0, n, NORMALS_CHUNK)):
        seq = np.random.SeedSequence([key, c])
        np.random.Generator(np.random.SFC64(seq)).standard_normal(
            out=ref[lo : lo + NORMALS_CHUNK]
        )
    got = np.full((n, 3), np.nan)
    normals.fill_chunks(key, NORMALS_CHUNK, got)
    np.testing.assert_array_equal(got, ref)


def test_standard_normals_keeps_numpys_numbers():
    """`standard_normals` beyond one chunk: the draws of NumPy's generators."""
    from robotlib.localization.motion import NORMALS_CHUNK, standard_normals

    n = 3 * NORMALS_CHUNK + 17
    got = standard_normals(np.random.default_rng(11), n)
    key = int(np.random.default_rng(11).integers(np.iinfo(np.int64).max))
    for c, lo in enumerate(range(0, n, NORMALS_CHUNK)):
        gen = np.random.Generator(np.random.SFC64(np.random.SeedSequence([key, c])))
        np.testing.assert_array_equal(
            got[lo : lo + NORMALS_CHUNK],
            gen.standard_normal((min(NORMALS_CHUNK, n - lo), 3)),
        )


@pytest.mark.parametrize("kind", ["beam", "paper"])
def test_keyed_threaded_step_equals_the_step_on_drawn_noise(corridor, kind):
    """The threaded step drawing its own noise: the numbers of the noise drawn first."""
    from robotlib.localization import (
        BeamParameters,
        BeamSensorModel,
        PaperSensorModel,
        _kernels,
        expected_readings,
    )

    n, rows, key = 7000, 1000, 4242424242
    rng = np.random.default_rng(2)
    p = corridor.sample_free_poses(n, 3)
    w = rng.random(n)
    w /= w.sum()
    noise = np.empty((n, 3))
    normals.fill_chunks(key, rows, noise)
    motion = (0.1, 0.3, -0.05, 0.02, 0.03, 0.01)
    z = expected_readings(corridor, np.array([corridor.start]))[0]
    if kind == "beam":
        model = BeamSensorModel(
            corridor, fast=True, params=BeamParameters(exponent=0.2)
        )
        m = model._model(z)
        extra = np.empty((len(z), len(model._norms[0])))
        _kernels.beam_scan_lut(*m, extra)
        args, ref_k, got_k = (
            (extra, m[2], 0.2),
            _kernels.lut_table_step_parallel,
            _kernels.lut_table_step_keyed_parallel,
        )
    else:
        model = PaperSensorModel(corridor, fast=True)
        k = np.arange(int(round(model.sonar.max_range * 1000)) + 1)
        terms = np.abs((z[:, None] - k * 0.001) / z[:, None])
        args, ref_k, got_k = (
            (terms, 1.0 / n),
            _kernels.paper_lut_step_parallel,
            _kernels.paper_lut_step_keyed_parallel,
        )
    table, where = model._where()
    s = model.sonar.sensors

    def outs():
        return (np.empty((n, 3)), np.empty(n), np.empty((n, 2)),
                np.empty((n, len(z)), dtype=np.int32))  # fmt: skip

    ref_o, got_o = outs(), outs()
    ref = ref_k(p, noise, motion, s, table, where, *args, w, *ref_o)
    got = got_k(p, key, rows, motion, s, table, where, *args, w, *got_o)
    assert got[:2] == ref[:2]
    np.testing.assert_array_equal(got[2], ref[2])
    for a, b in zip(got_o, ref_o, strict=True):
        np.testing.assert_array_equal(a, b)


# -- the filter's own PCG64, drawn in the small step's kernel (`_kernels.pcg64`) --


@pytest.mark.parametrize("seed", [0, 1, 12345, 2**64 - 1])
def test_pcg64_draws_are_numpys_and_advance_the_generator(seed):
    """Normals then a uniform, as `Generator.standard_normal(out=)` and `random()`."""
    from robotlib.localization._kernels import pcg64
    from robotlib.localization.motion import pcg64_words

    mine, ref = np.random.default_rng(seed), np.random.default_rng(seed)
    words = pcg64_words(mine)
    assert words is not None
    for n in (1, 7, 300, 20_000):  # 60,000 normals reach the ziggurat's tail
        out = np.empty((n, 3))
        pcg64.fill_normals(words, out)
        want = ref.standard_normal((n, 3))
        np.testing.assert_array_equal(out.view(np.uint64), want.view(np.uint64))
        assert pcg64.next_double(words) == ref.random()
        # the Python generator was advanced in place: it goes on as NumPy's
        assert mine.random() == ref.random()
        assert mine.bit_generator.state == ref.bit_generator.state


def test_pcg64_words_only_for_pcg64():
    from robotlib.localization.motion import pcg64_words

    assert pcg64_words(np.random.Generator(np.random.SFC64(0))) is None
    assert pcg64_words(np.random.Generator(np.random.PCG64DXSM(0))) is None


def test_small_step_draws_as_numpy_would(corridor):
    """The step's in-kernel draws leave the filter's generator where NumPy's would."""
    from robotlib.localization import (
        MCL,
        BeamParameters,
        BeamSensorModel,
        ThresholdResampling,
        expected_readings,
    )

    def make():
        sensor = BeamSensorModel(corridor, fast=True, params=BeamParameters())
        return MCL(corridor, sensor, n=300, rng=5, check=False,
                   resampling=ThresholdResampling("systematic", 1.0))  # fmt: skip

    a, b = make(), make()
    b._pcg = (b.rng.bit_generator, None)  # b draws with NumPy's methods
    z = expected_readings(corridor, np.array([corridor.start]))[0]
    odo = np.array(corridor.start)
    for k in range(3):
        step = (odo + [0.2 * k, 0.0, 0.03 * k], odo + [0.2 * k + 0.2, 0.0, 0.03 * k])
        np.testing.assert_array_equal(a.step(*step, z), b.step(*step, z))
        np.testing.assert_array_equal(a.particles, b.particles)
        assert a.rng.bit_generator.state == b.rng.bit_generator.state


@pytest.mark.parametrize("how", ["deepcopy", "pickle"])
def test_a_copied_filter_draws_from_its_own_generator(corridor, how):
    """A copy's step draws from the copy's generator (not a view of the original's)."""
    import copy
    import pickle

    from robotlib.localization import MCL

    a = MCL.paper(corridor, n=300, fast=True, rng=2)
    z = np.linspace(0.5, 2.5, len(a.sensor.sonar.sensors))
    odo = np.array(corridor.start)
    a.step(odo, odo + [0.2, 0.0, 0.02], z)  # the view is made
    b = copy.deepcopy(a) if how == "deepcopy" else pickle.loads(pickle.dumps(a))
    for m in (a, b):
        m.step(odo + [0.2, 0.0, 0.02], odo + [0.4, 0.0, 0.04], z)
    np.testing.assert_array_equal(a.particles, b.particles)
    assert a.rng.bit_generator.state == b.rng.bit_generator.state
