"""Pyramid: levels, filters, edits, spectra, .pyr files and bytes, pickling, threads."""

import multiprocessing
import pickle
import threading
import time
import warnings

import numpy as np
import pytest
from conftest import assert_same_bits, data

import meshpyr


def test_levels_run_from_the_base_to_every_vertex(sphere, sphere_pyramid):
    levels = sphere_pyramid.levels
    assert isinstance(levels, range) and levels.stop == len(sphere[0]) + 1
    assert 3 <= levels.start < 100
    assert_same_bits(sphere_pyramid.vertices, sphere[0])
    assert_same_bits(sphere_pyramid.faces, sphere[1])
    assert "926 vertices" in repr(sphere_pyramid)


def test_filters_keep_the_vertex_order_and_touch_only_their_bands(sphere, sphere_pyramid):
    v = sphere[0]
    top = sphere_pyramid.levels.stop - 1
    # A band above the finest level changes nothing (and says so).
    with pytest.warns(UserWarning, match="changes nothing"):
        same = sphere_pyramid.filter(stopband=[(top + 5, top + 50)])
    # Resynthesised from quantised details: within their bound (1e-6 of the diagonal).
    assert np.max(np.abs(same - v)) < 1e-6 * np.ptp(v)
    smooth = sphere_pyramid.filter(lowpass=100)
    assert smooth.shape == v.shape and smooth.dtype == np.float64
    rough = sphere_pyramid.filter(enhance=[(100, top, 2.0)])
    # Enhancing the details above level 100 twofold takes the mesh about twice as far from
    # the low-pass as the input is (not exactly: details live in frames of the coarser level).
    ratio = np.linalg.norm(rough - smooth) / np.linalg.norm(v - smooth)
    assert 1.5 < ratio < 2.5


def test_bands_in_feature_sizes_and_vertex_counts_agree(sphere_pyramid):
    spectrum = sphere_pyramid.spectrum()
    # The feature size of a band's upper level selects that level again.
    level, size = int(spectrum["hi"][2]), float(spectrum["feature_size"][2])
    assert_same_bits(sphere_pyramid.filter(lowpass=f"{size!r}u"), sphere_pyramid.filter(lowpass=level))


def test_the_spectrum_covers_every_detail_once(sphere_pyramid):
    spectrum = sphere_pyramid.spectrum()
    keys = {"lo", "hi", "levels", "details", "energy", "rms", "feature_size"}
    assert set(spectrum) == keys
    n = len(spectrum["lo"])
    assert n > 3 and all(len(a) == n for a in spectrum.values())
    assert spectrum["lo"].dtype == np.int64 and spectrum["energy"].dtype == np.float64
    assert_same_bits(spectrum["lo"][1:], spectrum["hi"][:-1])
    levels = sphere_pyramid.levels
    assert spectrum["lo"][0] == levels.start and spectrum["hi"][-1] == levels.stop - 1
    assert spectrum["levels"].sum() == len(levels) - 1
    assert np.all(spectrum["energy"] >= 0) and np.all(np.diff(spectrum["feature_size"]) < 0)


def test_an_edit_moves_the_region_around_the_point_and_leaves_far_vertices(sphere, sphere_pyramid):
    v = sphere[0]
    delta = np.array([0.0, 0.0, 3.0])
    edited = sphere_pyramid.edit(200, [(v[0], delta)], 5.0)
    moved = np.linalg.norm(edited - v, axis=1)
    distance = np.linalg.norm(v - v[0], axis=1)
    assert np.max(moved) > 1.0 and distance[np.argmax(moved)] < 5.0
    # The opposite cap of the sphere (radius 10) stays where it was but for the faint
    # reach of the coarse levels' predictions.
    assert np.max(moved[distance > 17.0]) < 1e-3 * np.linalg.norm(delta)


def test_bytes_files_and_pickles_give_back_the_same_pyramid(sphere_pyramid, tmp_path):
    blob = sphere_pyramid.to_bytes(details=False)
    assert isinstance(blob, bytes)
    path = tmp_path / "sphere.pyr"
    sphere_pyramid.save(path, details=False)
    assert path.read_bytes() == blob
    expected = sphere_pyramid.filter(stopband=[(50, 400)])
    for again in [
        meshpyr.Pyramid.from_bytes(blob),
        meshpyr.Pyramid.load(path),
        meshpyr.Pyramid.load(str(path)),
        pickle.loads(pickle.dumps(sphere_pyramid)),
        pickle.loads(pickle.dumps(sphere_pyramid, protocol=2)),
    ]:
        assert isinstance(again, meshpyr.Pyramid)
        assert again.levels == sphere_pyramid.levels and again.relax == sphere_pyramid.relax
        assert_same_bits(again.filter(stopband=[(50, 400)]), expected)
        assert again.to_bytes(details=False) == blob


def test_files_with_details_filter_within_their_bound_and_keep_their_bytes(sphere, sphere_pyramid, tmp_path):
    blob = sphere_pyramid.to_bytes()
    assert len(blob) > len(sphere_pyramid.to_bytes(details=False))
    path = tmp_path / "sphere-details.pyr"
    sphere_pyramid.save(path)
    assert path.read_bytes() == blob
    diagonal = np.linalg.norm(sphere[0].max(axis=0) - sphere[0].min(axis=0))
    expected = sphere_pyramid.filter(stopband=[(50, 400)])
    for again in [meshpyr.Pyramid.from_bytes(blob), meshpyr.Pyramid.load(path)]:
        assert np.max(np.abs(again.filter(stopband=[(50, 400)]) - expected)) < 1e-9 * diagonal
        assert_same_bits(again.filter(gains=[(50, 400, 1.0)]), sphere[0])
        assert again.to_bytes() == blob


def test_the_relaxation_travels_with_the_pyramid(sphere):
    pyramid = meshpyr.Pyramid(*sphere, relax="normal")
    assert pickle.loads(pickle.dumps(pyramid)).relax == "normal"


def _lowpass_in_a_worker(pyramid):
    return pyramid.filter(lowpass=100)


def test_pyramids_ship_to_worker_processes(sphere_pyramid):
    context = multiprocessing.get_context("spawn")
    with context.Pool(2) as pool:
        results = pool.map(_lowpass_in_a_worker, [sphere_pyramid, sphere_pyramid])
    for result in results:
        assert_same_bits(result, sphere_pyramid.filter(lowpass=100))


def test_the_gil_is_released_while_a_pyramid_is_built():
    """A Python thread keeps counting while the main thread builds the bunny's pyramid."""
    v, f = meshpyr.read(data("bunny.ply"))
    ticks = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks[0] += 1

    counter = threading.Thread(target=count)
    counter.start()
    try:
        time.sleep(0.05)
        before = ticks[0]
        start = time.perf_counter()
        meshpyr.Pyramid(v, f)
        elapsed = time.perf_counter() - start
        during = ticks[0] - before
    finally:
        stop.set()
        counter.join()
    # Holding the GIL, the counter would get at most a switch interval (5 ms) per call: a
    # few thousand ticks. Released, it counts all along, hundreds of thousands a second.
    assert elapsed > 0.1, f"the build took only {elapsed:.3f} s; too short to tell"
    assert during > 100_000 * elapsed, f"{during} ticks in {elapsed:.2f} s"


def test_threads_filter_one_shared_pyramid_at_once(sphere_pyramid):
    from concurrent.futures import ThreadPoolExecutor

    expected = sphere_pyramid.filter(lowpass=150)
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda _: sphere_pyramid.filter(lowpass=150), range(8)))
    for result in results:
        assert_same_bits(result, expected)


def test_filtering_without_a_band_is_refused(sphere_pyramid):
    with pytest.raises(ValueError, match="no filter given"):
        sphere_pyramid.filter(normal_only=True)


def test_a_lowpass_below_the_base_warns_and_acts_on_the_levels_there_are(sphere_pyramid):
    base = sphere_pyramid.levels.start
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        coarse = sphere_pyramid.filter(lowpass=1)
    assert any("coarsest level" in str(w.message) for w in caught)
    assert_same_bits(coarse, sphere_pyramid.filter(lowpass=base))


def test_a_move_that_reaches_no_vertex_warns_and_changes_nothing(sphere, sphere_pyramid):
    far_away = (100.0, 100.0, 100.0)
    with pytest.warns(UserWarning, match="reaches no vertex of level 200"):
        edited = sphere_pyramid.edit(200, [(far_away, (0.0, 0.0, 1.0))], 1.0)
    # Resynthesised from quantised details: within their bound (1e-6 of the diagonal).
    assert np.max(np.abs(edited - sphere[0])) < 1e-6 * np.ptp(sphere[0])
