"""The direct slicer's edge restore (issue 14, edgecomp's rule on the exact cross-section): the
restored print is the thinned one plus drops of thinned tracks inside the section within the
zone of an edge met along the radius, at edgecomp's gain; against shapely on a real layer."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from _direct_checks import section_geom
from rotoprint import ConfigError, load_device, load_mesh
from rotoprint.rotary import _direct_kernels as K
from rotoprint.rotary.deposit import DepositOptions
from rotoprint.rotary.direct import edge_offsets_mm, slice_rotary, union_pass_shares
from rotoprint.rotary.edgecomp import EdgeRestore
from rotoprint.rotary.interlace import plan_passes
from rotoprint.testing import box_mesh, torus_mesh

DEV = load_device("omnidot760")
HEAD = DEV.head


def _passes(mesh, **kw):
    kw = {"layer_height_mm": 1.0, "tilt_deg": 20.0, "inner_radius_mm": 60.0, **kw}
    base = slice_rotary(mesh, DEV, **kw)
    pp = plan_passes(HEAD, base.plan, footprint_um=DepositOptions().full_footprint_um(HEAD))
    shares, clock, _ = union_pass_shares(HEAD, base.plan, pp.offsets_mm, dpi_y=pp.dpi_y)
    plain = [slice_rotary(mesh, DEV, dpi_y=clock, pivot_offset_mm=o, **kw) for o in pp.offsets_mm]
    return plain, shares


def _local(job, seg):
    x0, y0 = job.part.model_to_local(seg.start[:, 0], seg.start[:, 1])
    x1, y1 = job.part.model_to_local(seg.end[:, 0], seg.end[:, 1])
    return x0, y0, x1, y1


def _zone(job, seg, ts, cuts=(), zone_um=50.0, backend="jit"):
    """``(F, N) bool``: the restore zone of every track of ``ts`` (gain 1 on a print without drops)."""
    part = _local(job, seg)
    n = ts.nozzle.size
    edge = ([np.stack(_local(job, c)) for c in cuts], np.arange(n), edge_offsets_mm(zone_um), np.ones(n), np.zeros(n))
    img = K.KERNELS[backend](*part, ts.r_mm ** 2, ts.psi0_rad, ts.nozzle, np.zeros(n), np.zeros(n), dphi=ts.dphi_rad,
                             direction=job.plan.direction, i0=ts.first_firing, n_f=ts.firings, n_cols=HEAD.nozzles,
                             fill=job.fill, level=1, edge=edge)
    return img > 0


@pytest.mark.parametrize("q", [0, 2])
def test_restored_drops_are_the_thinned_print_plus_zone_drops_at_the_gain(q):
    mesh = torus_mesh(6.0, 2.0, 96, 24)
    plain, shares = _passes(mesh)
    full = plain[q]
    thin = full.with_shares(shares[q], pass_index=q)
    rest = full.with_shares(shares[q], pass_index=q, edge_restore=EdgeRestore())
    assert rest.edge_restore_record()["offsets_um"] == [-50.0, 50.0]
    for L in (1, 2):
        seg, _ = full.segments(L)
        pf, pt, pr = full.layer(L), thin.layer(L), rest.layer(L)
        # the numpy reference (images of every real and virtual track) restores the same drops
        ref = slice_rotary(mesh, DEV, full.options.__class__(**{**full.options.as_dict(), "backend": "numpy"}),
                           shares=shares[q], pass_index=q, edge_restore=EdgeRestore()).layer(L)
        added = expected = 0.0
        for j, (ts, a, b, c, n) in enumerate(zip(full.tracks, pf.swathes, pt.swathes, pr.swathes, ref.swathes)):
            F, T, R = a.levels > 0, b.levels > 0, c.levels > 0
            assert np.array_equal(c.levels, n.levels)
            assert (T <= R).all() and (R <= F).all()  # a superset of the thinned print, within the full one
            new = R & ~T
            f = shares[q][j]
            thinned = np.zeros(HEAD.nozzles, bool)
            thinned[ts.nozzle] = (f[ts.nozzle] > 0) & (f[ts.nozzle] < 1)
            assert not new[:, ~thinned].any()  # only on thinned tracks
            zone = _zone(full, seg, ts)
            assert not (new & ~zone).any()  # only in the zone
            lost = zone & F & ~T
            s = np.minimum(1.0, 0.3 * f / np.maximum(1.0 - f, 1e-300))
            added += new.sum()
            expected += (lost.sum(axis=0) * np.where(thinned, s, 0.0)).sum()
        assert added > 50 and abs(added / expected - 1.0) < 0.1, (added, expected)


def test_no_zone_no_change_and_the_options():
    mesh = box_mesh((6.0, 1.0, 0.4))
    plain, shares = _passes(mesh, layer_height_mm=0.2)
    job = plain[1]
    a = job.with_shares(shares[1], pass_index=1).layer(0)
    # a coefficient so small that no track's restore pattern fires in its zone: the thinned print exactly
    b = job.with_shares(shares[1], pass_index=1, edge_restore=EdgeRestore(coefficient=1e-12)).layer(0)
    assert all(np.array_equal(x.levels, y.levels) for x, y in zip(a.swathes, b.swathes))
    # a cut far outside the section changes nothing; one through it restores beside its edges too
    seg, _ = job.segments(0)
    er = job.with_shares(shares[1], pass_index=1, edge_restore=EdgeRestore())
    p0 = er.print_from_segments(seg, layer_index=0)
    far = type(seg)(seg.start + [50.0, 0.0], seg.end + [50.0, 0.0], seg.start_edge, seg.end_edge)
    p1 = er.print_from_segments(seg, layer_index=0, cut=[far])
    assert all(np.array_equal(x.levels, y.levels) for x, y in zip(p0.swathes, p1.swathes))
    hole = box_mesh((0.6, 4.0, 0.4), origin=(-0.3, -2.0, 0.0))
    cut = slice_rotary(hole, DEV, layer_height_mm=0.2, tilt_deg=20.0, inner_radius_mm=60.0).segments(0)[0]
    p2 = er.print_from_segments(seg, layer_index=0, cut=[cut])
    assert sum(int((y.levels > 0).sum()) for y in p2.swathes) > sum(int((x.levels > 0).sum()) for x in p0.swathes)
    with pytest.raises(ConfigError, match="radial_only"):
        job.with_shares(shares[1], edge_restore=EdgeRestore(radial_only=False))
    with pytest.raises(ConfigError, match="thinned tracks"):
        slice_rotary(mesh, DEV, layer_height_mm=0.2, tilt_deg=20.0, inner_radius_mm=60.0, edge_restore=EdgeRestore())
    # a worker rebuilds the same restored pass from the JSON options
    import json

    again = slice_rotary(mesh, DEV, **json.loads(json.dumps(er.rotary_options)))
    assert again.edge_restore == er.edge_restore
    assert np.array_equal(again.layer(0).swathes[0].levels, p0.swathes[0].levels)


def test_zone_on_a_real_layer_matches_shapely(shared_meshes):
    """The 100 mm sphere's mid layer: a site is in the zone exactly when it is inside and the
    radial segment ``r +- 50 um`` through it leaves the exact section (trimesh + shapely), but
    within 1e-6 mm of a tie (the site, or the segment's ends, on the boundary)."""
    mesh = load_mesh(shared_meshes / "sphere_openscad.stl")
    job = slice_rotary(mesh, DEV, layer_height_mm=25.0, tilt_deg=20.0, inner_radius_mm=30.0, dpi_y=720.0)
    L = len(job) // 2
    seg, _ = job.segments(L)
    geom = section_geom(job, L)
    z_mm = 0.05
    checked = 0
    for ts in job.tracks:
        zone = _zone(job, seg, ts)[:, ts.nozzle]
        rows, tr = np.nonzero(np.ones_like(zone))
        pick = np.random.default_rng(ts.index).choice(rows.size, min(rows.size, 40000), replace=False)
        # and every zone site
        sel = np.unique(np.concatenate([pick, np.flatnonzero(zone.ravel())]))
        b, m = rows[sel], tr[sel]
        i = (b + ts.first_firing).astype(np.float64)
        ang = (ts.psi0_rad[m] + np.radians(job.part.angle_deg)) - job.plan.direction * i * ts.dphi_rad
        pts = {}
        for key, d in (("site", 0.0), ("lo", -z_mm), ("hi", z_mm)):
            r = ts.r_mm[m] + d
            pts[key] = job.part.platform_to_model(r * np.cos(ang), r * np.sin(ang))
        lines = shapely.linestrings(np.stack([np.stack(pts["lo"], -1), np.stack(pts["hi"], -1)], axis=1))
        inside = shapely.contains_xy(geom, *pts["site"])
        want = inside & ~shapely.contains(geom, lines)
        got = zone[b, m]
        bad = got != want
        if bad.any():
            near = np.minimum.reduce([shapely.distance(geom.boundary, shapely.points(*[p[0][bad], p[1][bad]]))
                                      for p in pts.values()])
            assert near.max() <= 1e-6, (int(bad.sum()), float(near.max()))
        checked += sel.size
        assert zone.any() or not inside.any()
    assert checked > 100_000
    # jit and numpy zones agree on this layer
    ts = job.tracks[0]
    assert np.array_equal(_zone(job, seg, ts), _zone(job, seg, ts, backend="numpy"))


def test_the_build_restores_edges_with_printer_edge_restore_true_and_not_by_default():
    from rotoprint.process import parse_job
    from rotoprint.process.plan import plan_job

    def plan(**printer):
        d = {"job": {"name": "small", "layer_height_mm": 0.05},
             "printer": {"device": "omnidot760", "tilt_deg": 20.0, **printer, "heads": [{"name": "H1", "ink": "ammonium_sulphate"},
                                                                          {"name": "H2", "ink": "calcium_chloride", "mount_angle_deg": 90.0},
                                                                          {"name": "H3", "ink": "silver_nitrate", "mount_angle_deg": 180.0},
                                                                          {"name": "H4", "ink": "ascorbate", "mount_angle_deg": 270.0}]},
             "placement": {"inner_radius_mm": 60.0},
             "parts": [{"name": "b", "material": "plaster", "priority": 1,
                        "shape": {"kind": "box", "size_mm": [3, 2, 0.05], "origin_mm": [0, 0, 0]}},
                       {"name": "c", "material": "silver", "priority": 3,
                        "shape": {"kind": "box", "size_mm": [0.8, 0.8, 0.05], "origin_mm": [1, 0.6, 0]}}]}
        return plan_job(parse_job(d, base_dir=".", source="small.toml"))

    on, off = plan(edge_restore=True), plan()
    h_on, h_off = on.head("ammonium_sulphate"), off.head("ammonium_sulphate")
    assert h_on.interlace["edge_restore"]["offsets_um"] == [-50.0, 50.0] and h_off.interlace["edge_restore"] is None
    secs = on.sections(0)
    n_on = n_off = 0
    for q in range(h_on.passes):
        a = off.material_print("plaster", h_off, secs, 0, pass_index=q)
        b = on.material_print("plaster", h_on, secs, 0, pass_index=q)
        inside = on.material_print("plaster", h_on, secs, 0, thinned=False, pass_index=q)
        for x, y, z in zip(a.swathes, b.swathes, inside.swathes):
            A, B, Z = x.levels > 0, y.levels > 0, z.levels > 0
            assert (A <= B).all() and (B <= Z).all()  # more drops, none inside the silver part (Z: plaster minus it)
        n_on += sum(int(y.levels.astype(bool).sum()) for y in b.swathes)
        n_off += sum(int(x.levels.astype(bool).sum()) for x in a.swathes)
    assert n_on > n_off, (n_on, n_off)
