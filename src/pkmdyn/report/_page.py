"""The self-contained HTML page: one copy of plotly.js inlined, the figures, tables and text.

The page needs no network and no server: plotly's JavaScript, every figure's data and the
summary figures (PNG, base64) are inside the one file. A small script ties the 3D view's time
slider to the time plots (a dotted vertical line at the slider's time).
"""

from __future__ import annotations

import base64
import html
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import PkmdynError
from ..io import atomic_file
from ._figures import Curve, TimePlot, decimate_minmax, scene_figure, time_figure, topology_figure
from ._scene import MAX_FRAMES, Scene, frame_indices
from ._topology import Topology, fundamental_loops

__all__ = ["write_report", "write_view", "REPORT_NAME"]

#: the report's file name inside a run's output folder
REPORT_NAME = "report.html"

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:0;color:#222;background:#fafafa}
header{background:#2c3e50;color:#fff;padding:14px 24px}header h1{margin:0;font-size:1.35em}
header p{margin:4px 0 0;color:#d5dde5;font-size:.9em}
main{padding:8px 24px 40px;max-width:1500px}
section{background:#fff;border:1px solid #e1e4e8;border-radius:6px;margin:14px 0;padding:10px 14px}
h2{font-size:1.1em;margin:4px 0 8px}.note{color:#555;font-size:.9em;margin:2px 0}
.grid{display:grid;grid-template-columns:repeat(auto-fill,minmax(560px,1fr));gap:10px}.grid>*{min-width:0}
.warn{color:#8a4b00;background:#fff4e0;border-left:4px solid #e67e22;padding:4px 8px;margin:4px 0}
table{border-collapse:collapse;font-size:.88em}td,th{border:1px solid #e1e4e8;padding:2px 8px;vertical-align:top;text-align:left}
th{background:#f3f5f7;font-weight:600}pre{background:#f6f8fa;padding:8px;overflow:auto;font-size:.85em;max-height:480px}
img{max-width:100%;border:1px solid #eee;margin:6px 0}figure{margin:0}figcaption{font-size:.85em;color:#555}
"""

_HOOK = """
window.addEventListener('unhandledrejection', function (e) {
  // plotly.js settles the promise of an animation step that another step replaces (a slider drag,
  // pause, a new play) by rejecting it without a reason; that is expected, not an error
  if (e.reason === undefined) { e.preventDefault(); }
});
(function () {
  var info = window.PKMDYN_REPORT;
  function mark(k) {
    var t = info.times[k];
    if (t === undefined) { return; }
    info.current = k;
    info.plots.forEach(function (id) {
      var el = document.getElementById(id);
      if (el && el.layout) {
        Plotly.relayout(el, {'shapes[0].x0': t, 'shapes[0].x1': t}).catch(function (err) {
          console.warn('time marker not moved', err);
        });
      }
    });
  }
  function hook() {
    var gd = document.getElementById(info.scene);
    if (!gd || !gd.on) { return false; }
    gd.on('plotly_animatingframe', function (e) { mark(parseInt(e.name, 10)); });
    gd.on('plotly_sliderchange', function (e) { mark(parseInt(e.step.value, 10)); });
    info.ready = true;
    return true;
  }
  if (!hook()) { window.addEventListener('load', hook); }
  // a plot drawn while the page was still being read took the width its cell had then: each
  // fits its cell once the whole grid is laid out
  window.addEventListener('load', function () {
    info.plots.forEach(function (id) {
      var el = document.getElementById(id);
      if (el && el.layout) { Plotly.Plots.resize(el); }
    });
  });
})();
"""


def _fmt(v: Any) -> str:
    if isinstance(v, bool) or v is None:
        return html.escape(str(v))
    if isinstance(v, (float, np.floating)):
        return f"{float(v):.6g}"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return html.escape(str(v))


def _table(obj: Any, depth: int = 0) -> str:
    """A nested mapping as nested tables; lists of scalars on one line, longer lists cut short."""
    if isinstance(obj, Mapping):
        rows = "".join(f"<tr><th>{html.escape(str(k))}</th><td>{_table(v, depth + 1)}</td></tr>" for k, v in obj.items())
        return f"<table>{rows}</table>"
    if isinstance(obj, (list, tuple)):
        if all(not isinstance(v, (Mapping, list, tuple)) for v in obj):
            shown = ", ".join(_fmt(v) for v in obj[:24])
            return f"[{shown}{', ...' if len(obj) > 24 else ''}]"
        return "".join(f"<div>{_table(v, depth + 1)}</div>" for v in obj[:50])
    return _fmt(obj)


def _div(fig: Any, div_id: str) -> str:
    import plotly.io as pio

    # a figure dictionary (the 3D scene) is written as built; a graph_objects figure was validated.
    # The scene waits for its play button (auto_play off): played on opening, every frame would also
    # move the time marker of every plot, redrawing them all while the reader scrolls through them
    return pio.to_html(fig, full_html=False, include_plotlyjs=False, div_id=div_id, validate=False,
                       auto_play=False, config={"displaylogo": False, "responsive": True})


def _plotly_js() -> str:
    from plotly.offline import get_plotlyjs

    return get_plotlyjs()


def _write_page(path: Path, title: str, subtitle: str, body: Sequence[str], info: Mapping[str, Any]) -> None:
    """Write the page to ``path`` piece by piece (plotly.js, some 5 MB, and the figures are not
    joined into one string first: a long run's report then costs its pieces, not three copies)."""
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                 f"<title>{html.escape(title)}</title><meta name=\"generator\" content=\"pkmdyn\">"
                 f"<style>{_CSS}</style><script>")
        fh.write(_plotly_js())
        fh.write(f"</script><script>window.PKMDYN_REPORT = {json.dumps(info)};</script></head><body>"
                 f"<header><h1>{html.escape(title)}</h1><p>{html.escape(subtitle)}</p></header><main>")
        for part in body:
            fh.write(part)
        fh.write(f"</main><script>{_HOOK}</script></body></html>\n")


def _decimated_plot(plot: TimePlot) -> TimePlot:
    """A plot with at most about :data:`MAX_PLOT_POINTS` points per curve (min-max bins)."""
    plain = [c for c in plot.curves if c.y is not None]
    if len(plain) != len(plot.curves) or not plain:
        return plot
    t, ys, dropped = decimate_minmax(np.asarray(plot.t, dtype=float), [np.asarray(c.y, dtype=float) for c in plain])
    if not dropped:
        return plot
    note = (plot.note + "; " if plot.note else "") + f"{len(t)} of {len(plot.t)} samples shown (min and max per bin)"
    return TimePlot(plot.title, plot.y_label, t, tuple(Curve(c.name, y) for c, y in zip(plain, ys)), note)


def write_report(out_folder: str | Path, *, title: str, scene: Scene | None, plots: Sequence[TimePlot] = (),
                 summary: Mapping[str, Any] | None = None, parameters: str = "", warnings: Sequence[str] = (),
                 images: Sequence[Path] = (), notes: Sequence[str] = (), max_frames: int = MAX_FRAMES,
                 scene_note: str = "", samples: int | None = None,
                 figures: Sequence[tuple[str, Any]] = ()) -> Path:
    """Write ``report.html`` into ``out_folder`` (a run's temporary output folder) and return it.

    ``scene``: the mechanism along the motion (animated at most ``max_frames`` frames, evenly
    spaced; the page says when samples were left out), or None; ``plots``: time plots, each
    marked at the slider's time; ``summary``: the run's summary (shown as tables);
    ``parameters``: the parameter file's text; ``warnings``: every warning of the run;
    ``images``: PNG summary figures embedded in the page; ``notes``: lines under the title;
    ``samples``: the samples of the motion when ``scene`` holds only some of them (already decimated);
    ``figures``: further interactive plotly figures ``(caption, figure)`` (e.g. 3D views).
    """
    folder = Path(out_folder)
    body: list[str] = []
    info: dict[str, Any] = {"scene": None, "plots": [], "times": [], "frames": 0, "samples": 0}
    t0 = 0.0
    if scene is not None:
        idx = frame_indices(scene.t.shape[0], max_frames)
        frames = scene.at(idx)
        t0 = float(frames.t[0])
        fig = scene_figure(frames, "Mechanism along the motion" if scene.frame_label == "t"
                           else f"Mechanism, one frame per {scene.frame_label}")
        total = max(int(samples or 0), int(scene.t.shape[0]))
        info.update(scene="pkmdyn-scene", times=[float(v) for v in frames.t], frames=int(idx.size), samples=total)
        lines = [scene_note] if scene_note else []
        if idx.size < total:
            lines.append(f"Decimated: {idx.size} frames at evenly spaced samples of the {total} samples "
                         f"({scene.t[0]:.6g} s to {scene.t[-1]:.6g} s).")
        else:
            lines.append(f"Every one of the {total} samples is a frame.")
        meta = fig["layout"]["meta"]
        speed = ("\u00d71 plays the motion in real time" if meta["realtime"]
                 else f"\u00d71 shows one frame every {meta['frame_ms']:.0f} ms")
        lines.append(f"Drag to orbit, scroll to zoom; {speed}. Actuated chains are coloured by their effort "
                     "(red pushing/positive, blue negative, white zero).")
        body.append("<section id=\"animation\"><h2>3D animation</h2>" + "".join(
            f"<p class=\"note\">{html.escape(x)}</p>" for x in lines) + _div(fig, "pkmdyn-scene") + "</section>")
    if plots:
        divs = []
        for k, p in enumerate(plots):
            div_id = f"pkmdyn-plot-{k}"
            info["plots"].append(div_id)
            divs.append(f"<div class=\"timeplot\">{_div(time_figure(_decimated_plot(p), t0), div_id)}</div>")
        body.append("<section id=\"plots\"><h2>Plots</h2><p class=\"note\">The dotted red line marks the 3D "
                    "view's time.</p><div class=\"grid\">" + "".join(divs) + "</div></section>")
    if figures:
        divs = [f"<figure>{_div(fig, f'pkmdyn-figure-{k}')}<figcaption>{html.escape(cap)}</figcaption></figure>"
                for k, (cap, fig) in enumerate(figures)]
        body.append("<section id=\"views\"><h2>3D views</h2><p class=\"note\">Drag to orbit, scroll to zoom."
                    "</p>" + "".join(divs) + "</section>")
    if images:
        figs = []
        for p in images:
            try:
                data = base64.b64encode(Path(p).read_bytes()).decode("ascii")
            except OSError as exc:
                raise PkmdynError(f"report: cannot read the figure {p} ({exc.strerror})") from None
            figs.append(f"<figure><img alt=\"{html.escape(Path(p).name)}\" src=\"data:image/png;base64,{data}\">"
                        f"<figcaption>{html.escape(Path(p).name)}</figcaption></figure>")
        body.append("<section id=\"figures\"><h2>Summary figures</h2>" + "".join(figs) + "</section>")
    warn = "".join(f"<div class=\"warn\">{html.escape(w)}</div>" for w in warnings) or \
        "<p class=\"note\">The run raised no warning.</p>"
    body.append(f"<section id=\"warnings\"><h2>Warnings ({len(warnings)})</h2>{warn}</section>")
    if summary is not None:
        body.append(f"<section id=\"summary\"><h2>Summary</h2>{_table(summary)}</section>")
    if parameters:
        body.append(f"<section id=\"parameters\"><h2>Parameters used</h2><pre>{html.escape(parameters)}</pre></section>")
    path = folder / REPORT_NAME
    try:
        _write_page(path, title, " | ".join(notes) if notes else "pkmdyn report", body, info)
    except OSError as exc:
        raise PkmdynError(f"cannot write {path} ({exc.strerror or type(exc).__name__})") from None
    return path


def write_view(path: str | Path, *, title: str, scene: Scene, topology: Topology, mobility: Mapping[str, Any],
               parameters: str = "", notes: Sequence[str] = (), inputs: Mapping[str, Any] | None = None,
               listing: Any = None) -> Path:
    """Write the ``view`` page of a machine to ``path`` through :func:`pkmdyn.io.atomic_file` (the
    output rule: only a new name or a file pkmdyn wrote is replaced, never one of ``inputs``):
    the mechanism at one pose in 3D, the topology graph with its loops, and the mobility and
    over-constraint counts (``mobility``). ``listing``, when given, is called with the path before
    the file moves into place (the command line prints it there)."""
    target = Path(path)
    loops = fundamental_loops(topology)
    info: dict[str, Any] = {"scene": "pkmdyn-scene", "plots": [], "times": [float(scene.t[0])], "frames": 1,
                            "samples": 1}
    fig = scene_figure(scene.at(np.array([0])), "Mechanism at its home pose")
    fig["layout"]["updatemenus"], fig["layout"]["sliders"], fig["frames"] = [], [], []  # one pose: nothing to play
    counts = {"bodies (ground included)": len(topology.bodies), "joints": len(topology.joints),
              "actuated joints": ", ".join(topology.actuated) or "none", "cut joints": ", ".join(topology.cuts),
              "independent loops": len(loops), **mobility}
    loop_rows = "".join(f"<tr><th>{k + 1}</th><td>{html.escape(' - '.join(lp))}</td></tr>" for k, lp in enumerate(loops))
    kinds: dict[str, list[str]] = {}
    for name, kind, _, _ in topology.joints:
        kinds.setdefault(kind, []).append(name)
    kind_rows = "".join(f"<tr><th>{html.escape(k)}</th><td>{len(v)}</td><td>{html.escape(', '.join(v))}</td></tr>"
                        for k, v in kinds.items())
    body = [
        "<section id=\"animation\"><h2>3D view</h2><p class=\"note\">Drag to orbit, scroll to zoom; hover a joint "
        "for its name.</p>" + _div(fig, "pkmdyn-scene") + "</section>",
        f"<section id=\"mobility\"><h2>Mobility and over-constraints</h2>{_table(counts)}</section>",
        "<section id=\"topology\"><h2>Topology</h2><p class=\"note\">Edges: joints, coloured by type; thick: "
        "actuated; dashed: cut joints (opening them leaves a spanning tree; each closes one loop).</p>"
        + _div(topology_figure(topology, loops), "pkmdyn-topology")
        + f"<h2>Joints by type</h2><table><tr><th>type</th><th>count</th><th>joints</th></tr>{kind_rows}</table>"
        + f"<h2>Loops (one per cut joint)</h2><table>{loop_rows}</table></section>",
    ]
    if parameters:
        body.append(f"<section id=\"parameters\"><h2>Parameters used</h2><pre>{html.escape(parameters)}</pre></section>")
    with atomic_file(target, inputs=dict(inputs or {})) as tmp:
        _write_page(tmp, title, " | ".join(notes) if notes else "pkmdyn view", body, info)
        if listing is not None:
            listing(target)
    return target
