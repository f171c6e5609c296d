"""The build report: one HTML file that opens from disk with no network.

Sections: summary and warnings, layer viewer (slider: composite of the materials, the layer's
ordered passes and its print-ready images), thickness and density plots, head geometry,
simulator overlays, printability findings, estimates (thickness, resistance with the hand
check). Everything is inline: CSS, a small script, and images as ``data:`` URIs.
"""

from __future__ import annotations

import base64
import html
import json
import math
from pathlib import Path

import numpy as np

from .plots import density_figure, head_geometry_figure, thickness_figure, time_figure

__all__ = ["render_report", "MAX_VIEWER_LAYERS", "MAX_PRINT_IMAGE_LAYERS"]

#: The viewer embeds at most this many layers' composites (sampled evenly beyond).
MAX_VIEWER_LAYERS = 400
#: ... and the print-ready images of at most this many layers.
MAX_PRINT_IMAGE_LAYERS = 120

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:0;color:#222;background:#fafafa}
header{background:#23324a;color:#fff;padding:14px 24px}header h1{margin:0;font-size:22px}
header p{margin:4px 0 0;opacity:.85}main{padding:8px 24px 40px;max-width:1300px}
section{background:#fff;border:1px solid #ddd;border-radius:6px;padding:12px 18px;margin:14px 0}
h2{font-size:18px;margin:4px 0 10px}table{border-collapse:collapse;font-size:13px;margin:6px 0}
td,th{border:1px solid #ddd;padding:3px 8px;text-align:left;vertical-align:top}th{background:#f0f2f5}
.warn{background:#fff6e0;border-left:4px solid #e0a000;padding:6px 10px;margin:4px 0;font-size:13px}
.ok{color:#1a7f37;font-weight:600}.bad{color:#c62828;font-weight:600}
.viewer{display:flex;gap:18px;flex-wrap:wrap}.viewer .left{flex:0 0 auto}.viewer .right{flex:1 1 400px;min-width:320px}
#layerImg{image-rendering:pixelated;border:1px solid #aaa;width:440px;height:auto;background:#fff}
.prints{display:flex;flex-wrap:wrap;gap:8px}.prints figure{margin:0;font-size:11px;width:180px}
.prints img{width:180px;height:110px;object-fit:fill;image-rendering:pixelated;border:1px solid #bbb;background:#000}
.legend span{display:inline-block;margin-right:12px;font-size:13px}.sw{display:inline-block;width:12px;height:12px;border:1px solid #777;vertical-align:middle;margin-right:4px}
img.plot{max-width:100%;height:auto}.ovl{display:flex;flex-wrap:wrap;gap:12px}.ovl figure{margin:0;font-size:12px}
.ovl img{max-width:300px;image-rendering:pixelated;border:1px solid #aaa}code{background:#f3f3f3;padding:0 3px}
"""

_JS = """
(function(){
  var data = JSON.parse(document.getElementById('layer-data').textContent);
  var slider = document.getElementById('layerSlider');
  var img = document.getElementById('layerImg');
  var label = document.getElementById('layerLabel');
  var passes = document.getElementById('passTable');
  var prints = document.getElementById('prints');
  function esc(s){return String(s).replace(/[&<>"]/g,function(c){return {'&':'&amp;','<':'&lt;','>':'&gt;','"':'&quot;'}[c];});}
  function show(k){
    var L = data.layers[k];
    img.src = L.composite;
    img.setAttribute('data-layer', String(L.index));
    label.textContent = 'layer ' + L.index + ' of ' + (data.n_layers - 1) + ', z ' + L.z0.toFixed(4) + '-' + L.z1.toFixed(4) + ' mm, about ' + (L.time_s/60).toFixed(1) + ' min';
    var rows = '<tr><th>#</th><th>material</th><th>cycles</th><th>per cycle, in order (head: ink x repeats)</th><th>drops per pass</th><th>after</th><th>thickness um</th></tr>';
    if (!L.blocks.length) rows += '<tr><td colspan=7>nothing printed in this layer</td></tr>';
    L.blocks.forEach(function(b, i){
      var seq = b.passes_per_cycle.map(function(p){return esc(p.head)+': '+esc(p.ink)+' x '+p.repeats+(p.wait_s? ' (wait '+p.wait_s+' s)':'');}).join(' &rarr; ');
      var drops = Object.keys(b.drops_per_pass).map(function(k){return esc(k)+' '+b.drops_per_pass[k];}).join('<br>');
      rows += '<tr><td>'+(i+1)+'</td><td>'+esc(b.material)+'</td><td>'+b.cycles+' ('+b.passes+' passes)</td><td>'+seq+'</td><td>'+drops+'</td><td>'+(b.post_steps.map(esc).join('<br>')||'-')+'</td><td>'+b.thickness_um[0].toPrecision(3)+(b.thickness_um[1]>b.thickness_um[0]*1.001?'-'+b.thickness_um[1].toPrecision(3):'')+'</td></tr>';
    });
    passes.innerHTML = rows;
    var h = '';
    (L.prints || []).forEach(function(p){h += '<figure><img alt="print image" src="'+p.src+'"><figcaption>'+esc(p.caption)+'</figcaption></figure>';});
    if (!L.prints) h = '<p>print-ready images of this layer: see the layers/ folder</p>';
    prints.innerHTML = h;
  }
  slider.addEventListener('input', function(){show(parseInt(slider.value, 10));});
  show(parseInt(slider.value, 10));
})();
"""


def _uri(png: bytes) -> str:
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def _e(x) -> str:
    return html.escape(str(x))


def _fmt(v, nd=4) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        if not math.isfinite(v):
            return "inf" if v > 0 else "-"
        return f"{v:.{nd}g}"
    return _e(v)


def _print_thumb(path: Path) -> str:
    return _uri(path.read_bytes())


def render_report(plan, plan_json: dict, *, composites: list[bytes], overlays_dir: Path) -> str:
    """The HTML text of the report.

    Parameters
    ----------
    plan : BuildPlan
    plan_json : dict
        What ``plan.json`` holds.
    composites : list of bytes
        PNG of every layer's composite (materials in their colours), one per layer.
    overlays_dir : Path
        The output folder being written (overlays and print images are read from it).
    """
    from .colours import material_colour

    order = plan.material_order
    colours = {m: material_colour(m, order) for m in order}
    layers = plan_json["layers_detail"]
    n = len(layers)
    idx = list(range(n)) if n <= MAX_VIEWER_LAYERS else sorted(set(np.linspace(0, n - 1, MAX_VIEWER_LAYERS).round().astype(int).tolist()))
    with_prints = set(idx if len(idx) <= MAX_PRINT_IMAGE_LAYERS else np.array(idx)[np.linspace(0, len(idx) - 1, MAX_PRINT_IMAGE_LAYERS).round().astype(int)].tolist())
    vlayers = []
    for i in idx:
        L = layers[i]
        d = {"index": i, "z0": L["z_bottom_mm"], "z1": L["z_top_mm"], "time_s": L["time_s"], "blocks": L["blocks"],
             "composite": _uri(composites[i])}
        if i in with_prints:
            pr = []
            for im in L["images"]:
                for s in im["swathes"]:
                    pr.append({"src": _print_thumb(overlays_dir / s["file"]),
                               "caption": f"{im['head']}: {im['material']} / {im['ink']}, {s['drops']} drops, "
                                          f"{s['firings']} firings x {plan.device.head.nozzles} nozzles"})
            d["prints"] = pr
        vlayers.append(d)
    layer_data = json.dumps({"n_layers": n, "layers": vlayers}).replace("</", "<\\/")

    sp = plan.job.spec
    parts = []
    w = parts.append
    w("<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>rotoprint build: " + _e(sp.job.name) + "</title>")
    w("<link rel='icon' href='data:,'><meta name='viewport' content='width=device-width'>")
    w(f"<style>{_CSS}</style></head><body>")
    t_h = plan_json["estimated_print_time_s"] / 3600
    w(f"<header><h1>{_e(sp.job.name)}</h1><p>{_e(sp.job.description)} &middot; {n} layers of {sp.job.layer_height_mm:g} mm "
      f"&middot; {len(plan.heads)} heads ({_e(plan.device.name)}, tilt {plan.heads[0].tilt_deg:g} deg) &middot; "
      f"estimated printing time {t_h:.1f} h &middot; rotoprint {_e(plan_json['rotoprint'])}</p></header><main>")
    # summary
    w("<section id='summary'><h2>Summary</h2><table><tr><th>material</th><th>parts (priority)</th><th>inks in order</th>"
      "<th>after</th><th>cycles / layer</th><th>passes / layer</th><th>thickness / layer (um)</th></tr>")
    for m in order:
        mat = plan.job.materials[m]
        est = plan.estimates[m]
        ps = ", ".join(f"{p.name} ({p.priority})" for p in sp.parts if p.material == m)
        inks = " &rarr; ".join(f"{_e(i.name)} x {i.repeats} (head {_e(plan.head(i.name).name)})" for i in mat.inks)
        post = "<br>".join(_e(s.describe()) for s in mat.post_steps) or "-"
        sw = f"<span class='sw' style='background:rgb{colours[m]}'></span>"
        w(f"<tr><td>{sw}{_e(m)}</td><td>{_e(ps)}</td><td>{inks}</td><td>{post}</td><td>{est.cycles} (needed {est.cycles_needed})</td>"
          f"<td>{est.passes_per_layer}</td><td>{_fmt(est.per_layer_um[0])} - {_fmt(est.per_layer_um[1])}</td></tr>")
    w("</table>")
    w("<p style='font-size:13px'>Cycles per layer follow from the true volume per area of the planned drops: the drops "
      "of every interlaced pass of the material's first layer landing in its interior (the design less half a footprint), "
      "per 1 mm radial bin of the interior's area (not a nominal density); with interlaced passes they are a multiple "
      "of the passes.</p>")
    cov = plan_json.get("coverage") or {}
    if cov:
        h0 = plan.heads[0]
        cells = next((o["deposit"]["grid_um"] for o in plan_json.get("overlays", []) if o.get("deposit")), None)
        on = (f"on the film grid ({cells[0]:.1f} x {cells[1]:.1f} um cells) against the design rasterised at the cells' "
              "centres" if cells else "on the film grid")
        w("<h3>Film coverage (deposit model)</h3>"
          f"<p style='font-size:13px'>{h0.passes} interlaced pass(es) per layer, radial offsets "
          f"{', '.join(f'{o * 1000:.1f}' for o in h0.pass_offsets_mm)} um, clock {h0.lattice.dpi_y:.0f} dpi "
          f"({_e(h0.interlace.get('clock', 'job'))}). Each layer's drops of every pass and ink spread to footprints and merged "
          f"{on}; the interior is the design less a band half a footprint wide. The cell model's IoU is secondary.</p>"
          "<table id='coverage'><tr><th>material</th><th>layers</th><th>interior uncovered</th><th>band uncovered</th>"
          "<th>thinnest / mean</th><th>thinnest / mean as landed</th><th>cell model IoU</th></tr>")
        for m, c in cov.items():
            basis = c.get("thinnest_to_mean_basis", "as landed")
            w(f"<tr><td>{_e(m)}</td><td>{', '.join(str(x) for x in c['layers'])}</td><td><b>{100 * c['uncovered_fraction']:.2f} %</b></td>"
              f"<td>{100 * c['band_uncovered_fraction']:.2f} %</td><td><b>{_fmt(c['thinnest_to_mean'])}</b> ({_e(basis)})</td>"
              f"<td>{_fmt(c.get('thinnest_to_mean_as_landed', c['thinnest_to_mean']))}</td>"
              f"<td>{_fmt(c['cell_model_iou'])}</td></tr>")
        w("</table>")
        words = []
        for m, c in cov.items():
            if c.get("thinnest_to_mean_basis") == "levelled":
                pars = "; ".join(f"{_e(p['ink'])}: set time {p['set_time_s']:g} s, viscosity {p['viscosity_mpa_s']:g} mPa s, "
                                 f"surface tension {p['surface_tension_mn_m']:g} mN/m" for p in c.get("levelling", []))
                words.append(f"{_e(m)} ({pars})")
        if words:
            w("<p style='font-size:13px'>Thinnest / mean is that of the <b>levelled</b> film for " + ", ".join(words) +
              ": the wet film flows under surface tension before it sets (linearised thin-film equation, Orchard 1962; "
              "h0 the 10th percentile of the as-landed wet film; nominal ink figures unless the ink gives its own). "
              "The uncovered fractions are as landed: levelling does not fill a dry pinhole.</p>")
        else:
            w("<p style='font-size:13px'>Thinnest / mean is that of the film as landed (no ink levels: set time 0 s).</p>")
    if plan_json.get("layer_parts"):
        w("<h3>CAD layers</h3><table id='cad-layers'><tr><th>part</th><th>material</th><th>file</th><th>z (mm)</th>"
          "<th>area (mm2)</th><th>regions / holes</th><th>narrowest track / gap (mm)</th><th>terminals</th></tr>")
        for lp in plan_json["layer_parts"]:
            sw = f"<span class='sw' style='background:rgb{colours.get(lp['material'], (128, 128, 128))}'></span>"
            holes = f" minus {', '.join(lp['holes_from'])}" if lp["holes_from"] else ""
            w(f"<tr><td>{_e(lp['part'])}</td><td>{sw}{_e(lp['material'])}</td><td>{_e(lp['file'])} ({_e(lp['format'])}){_e(holes)}</td>"
              f"<td>{lp['z_mm'][0]:g} - {lp['z_mm'][1]:g}</td><td>{lp['area_mm2']:.4f}</td><td>{lp['regions']} / {lp['holes']}</td>"
              f"<td>{_fmt(lp['narrowest_track_mm'])} / {_fmt(lp['narrowest_gap_mm'])}</td><td>{_e(', '.join(lp['terminals']) or '-')}</td></tr>")
        w("</table>")
    if plan.warnings:
        w("<h3>Warnings</h3>" + "".join(f"<div class='warn'>{_e(x)}</div>" for x in plan.warnings))
    w("</section>")
    # viewer
    legend = "".join(f"<span><span class='sw' style='background:rgb{colours[m]}'></span>{_e(m)}</span>" for m in order)
    w("<section id='viewer'><h2>Layer viewer</h2><div class='viewer'><div class='left'>"
      f"<input type='range' id='layerSlider' min='0' max='{len(vlayers) - 1}' value='0' step='1' style='width:440px'>"
      "<div id='layerLabel'></div><img id='layerImg' alt='layer composite'><div class='legend'>" + legend + "</div>"
      "<p style='font-size:12px;max-width:440px'>Materials of the layer after overlaps are resolved by priority, on the "
      "assembly's grid at the head's pitch (model +X = radially outwards = right, +Y = along the turn = up).</p></div>"
      "<div class='right'><table id='passTable'></table><h3>Print-ready images (rows = firings, columns = nozzles)</h3>"
      "<div class='prints' id='prints'></div></div></div>")
    if len(vlayers) < n:
        w(f"<p>The viewer shows {len(vlayers)} of {n} layers, evenly spaced; every layer is in <code>layers/</code>.</p>")
    w("</section>")
    # plots
    w("<section id='plots'><h2>Thickness and drop density</h2>")
    w(f"<img class='plot' alt='thickness' src='{_uri(thickness_figure(plan, colours))}'>")
    w(f"<img class='plot' alt='density' src='{_uri(density_figure(plan))}'>")
    w(f"<img class='plot' alt='time per layer' src='{_uri(time_figure(layers))}'>")
    w("<table><tr><th>material</th><th>ink</th><th>wet film per pass (um)</th></tr>")
    for m in order:
        for ink, (a, b) in plan.estimates[m].per_pass_wet_um.items():
            w(f"<tr><td>{_e(m)}</td><td>{_e(ink)}</td><td>{_fmt(a)} - {_fmt(b)}</td></tr>")
    w("</table></section>")
    # heads
    w("<section id='heads'><h2>Head geometry</h2><div class='viewer'><div class='left'>"
      f"<img class='plot' style='max-width:560px' alt='head geometry' src='{_uri(head_geometry_figure(plan, colours))}'></div>"
      "<div class='right'><table><tr><th>head</th><th>ink</th><th>mount deg</th><th>tilt deg</th><th>swathes (pivot mm)</th>"
      "<th>revolution s</th><th>drops/mm2</th></tr>")
    for h in plan.heads:
        piv = ", ".join(f"{s.pivot_radius_mm:.2f}" for s in h.lattice.plan.swathes)
        w(f"<tr><td>{_e(h.name)}</td><td>{_e(h.ink)}</td><td>{h.mount_angle_deg:g}</td><td>{h.tilt_deg:g}</td><td>{piv}</td>"
          f"<td>{', '.join(f'{r:.2f}' for r in h.revolution_s)}</td><td>{h.density_per_mm2.min():.1f} - {h.density_per_mm2.max():.1f}</td></tr>")
    w("</table></div></div></section>")
    # overlays
    w("<section id='overlays'><h2>Simulator overlays</h2><p style='font-size:13px'>Drops placed by the forward formula "
      "from the print-ready data; the headline is the deposit model's film (each drop's volume spread to a footprint and merged; "
      "interior = the region less half a footprint), the cell-model IoU is secondary. Overlay (coverage before density "
      "thinning), against the material's exact region: light blue "
      "printed, orange uncovered, pink printed outside, dark blue / red drops on / off the design.</p><div class='ovl'>")
    for o in plan_json["overlays"]:
        w(f"<figure><img alt='overlay' src='{_print_thumb(overlays_dir / o['file'])}'><figcaption>layer {o['layer']} "
          f"{_e(o['material'])} ({_e(o['head'])}): {_film_caption(o)}cell model IoU {o['iou']:.4f}, uncovered {100 * o['uncovered_fraction']:.2f} %</figcaption></figure>")
    w("</div></section>")
    # printability
    w("<section id='printability'><h2>Printability</h2>")
    if not plan_json["printability"]:
        w("<p>Not run (process.check = false).</p>")
    else:
        w("<table><tr><th>part</th><th>material</th><th>result</th><th>findings</th><th>thinnest wall</th><th>narrowest gap</th></tr>")
        for c in plan_json["printability"]:
            cnt = ", ".join(f"{k} {v}" for k, v in c["counts"].items() if v) or "none"
            tw = c["thinnest_wall"]
            ng = c["narrowest_gap"]
            w(f"<tr><td>{_e(c['part'])}</td><td>{_e(c['material'])}</td><td class='{'ok' if c['ok'] else 'bad'}'>"
              f"{'ok' if c['ok'] else 'falls short'}</td><td>{_e(cnt)}</td>"
              f"<td>{_fmt(tw['width_mm'] * 1000) + ' um' if tw else '-'}</td><td>{_fmt(ng['width_mm'] * 1000) + ' um' if ng else '-'}</td></tr>")
        w("</table>")
        lim = plan_json["printability"][0]["limits"]
        w(f"<details><summary>device limits</summary><pre>{_e(json.dumps(lim, indent=1, default=str))}</pre></details>")
        for c in plan_json["printability"]:
            if c.get("overlay"):
                w(f"<figure><img alt='check overlay' style='max-width:400px' src='{_print_thumb(overlays_dir / c['overlay'])}'>"
                  f"<figcaption>{_e(c['part'])}: first layer with findings</figcaption></figure>")
    w("</section>")
    # estimates
    w("<section id='estimates'><h2>Electrical estimates</h2>")
    if not plan_json["resistance"] and not plan_json["interdigitated"]:
        w("<p>No resistance requested in the job.</p>")
    for r in plan_json["resistance"]:
        if "error" in r:
            w(f"<div class='warn'>{_e(r['part'])} {_e(' - '.join(r['between']))}: {_e(r['error'])}</div>")
            continue
        d, p, hc = r["design"], r["printed"], r["hand_check"]
        w(f"<h3>{_e(r['part'])}: {_e(r['between'][0])} to {_e(r['between'][1])}</h3><table>"
          "<tr><th>estimate</th><th>resistance</th><th>pixels solved</th></tr>"
          f"<tr><td>exact region, grid / {d['oversample']}</td><td>{_fmt(d['resistance_ohm'])} ohm</td><td>{d['unknowns']}</td></tr>"
          f"<tr><td>deposited film (the planned drops of every pass)</td><td>{_fmt(p['resistance_ohm'])} ohm</td><td>{p['unknowns']}</td></tr>")
        if hc:
            w(f"<tr><td>hand check: {_e(hc['formula'])}; L = {hc['track_length_mm']:.2f} mm, w = {hc['track_width_mm']:g} mm, "
              f"{hc['corners']} corners, t = {hc['thickness_um']:.3g} um, R_s = {hc['sheet_resistance_ohm']:.4g} ohm/sq</td>"
              f"<td>{_fmt(hc['resistance_ohm'])} ohm</td><td>-</td></tr>")
        w("</table>")
        if not d["connected"]:
            w("<p>The terminals are not connected (open circuit).</p>")
    for name, v in plan_json["interdigitated"].items():
        w(f"<p>{_e(name)}: cell constant {v['cell_constant_per_mm']:.4g} /mm ({_e(v['note'])}).</p>")
    w("</section>")
    w("<section id='files'><h2>Files</h2><p><code>plan.json</code> holds every number of this report; "
      "<code>layers/layer_NNNNN/MATERIAL-INK.png</code> (with its <code>.json</code> sidecar, readable by "
      "<code>rotoprint simulate</code>) are the print-ready images.</p></section>")
    w(f"</main><script type='application/json' id='layer-data'>{layer_data}</script><script>{_JS}</script></body></html>")
    return "".join(w_ for w_ in parts)


def _film_caption(o: dict) -> str:
    """Headline of an overlay: the deposit model's film (rotary/deposit.py), when recorded."""
    f = o.get("deposit")
    if not f:
        return ""
    lv = f.get("levelled")
    ttm = (f"thinnest / mean {lv['thinnest_to_mean']:.2f} levelled ({lv['set_time_s']:g} s), {f['thinnest_to_mean']:.2f} as landed"
           if lv else f"thinnest / mean {f['thinnest_to_mean']:.2f} as landed")
    return (f"<b>film: {100 * f['uncovered_fraction']:.2f} % of the interior uncovered</b> "
            f"({f['footprint_um']:.0f} um footprints; {ttm}); ")
