"""Where headless Chromium's time goes when it opens a generated page, and what each kind of SVG element costs.

Input: bench/generate.py's 3-minute THCHS-30 recording (built at bench time), made into the
audio-book and the announcer page (default options). `python -m bench.page [FOLDER ...]` measures
existing page folders instead; `python -m bench.page --compare BEFORE AFTER [...]` compares pairs of
page folders of one recording (elements per kind per minute, page ready, playback: interleaved).

Figures, each the median of RUNS loads from file:// with the variants interleaved (the machine is shared):
- page ready: navigation start to two animation frames after the `load` event (performance.now());
- the split of that time: HTML parse (responseEnd to domInteractive: the inline SVG's DOM and the
  page script run there), the rest to the `load` event (the audio element's metadata, the CSS),
  first paint, and Chromium's own counters (CDP Performance.getMetrics: style, layout, script);
- a plain page of the same size (the SVG's bytes in an HTML comment) as the yardstick, and the
  page with animation.svg inline as written (before render/pages.py undisplayed the drawings);
- variants made by post-processing animation.svg (never the writer), each put in the page the way
  render/pages.py does: without the page script, without the audio element, with every other
  drawing of each track dropped, with `<set>` runs instead of one discrete `<animate href>`, with
  presentation attributes instead of CSS classes, without clip paths, with the path data doubled.
  The difference to the page as made, divided by the elements (or KB) changed, is their cost;
- playback: main-thread task time per second of the free-running SVG (CDP TaskDuration);
- with `--compare`, also the renderer main thread's CPU time (thread time of a trace, which a loaded
  machine stretches far less than wall time): to ready, of its style updates (UpdateLayoutTree: the
  style and the shadow trees of every `<use>`, docs/BENCHMARKS.md "Page style work"), and per second
  of playing.
"""

from __future__ import annotations

import json
import re
import shutil
import statistics
import sys
import tempfile
from collections import Counter
from collections.abc import Callable
from pathlib import Path

from lxml import etree

from bench.generate import CHROMIUM_ARGS, READY_PROBE, build_input
from cartoonface.render.pages import inline_svg

RUNS = 5
SVG_NS = "{http://www.w3.org/2000/svg}"
PLAY_SECONDS = 2.0
VIEWPORT = {"width": 1280, "height": 800}
SPLIT = """() => { const n = performance.getEntriesByType('navigation')[0];
    const paint = performance.getEntriesByType('paint').find(e => e.name === 'first-paint');
    return {ready: window.__cfReady, read: n.responseEnd, parse: n.domInteractive - n.responseEnd,
            load: n.loadEventStart - n.domInteractive, paint: paint ? paint.startTime : NaN}; }"""
COUNTERS = ("RecalcStyleDuration", "LayoutDuration", "ScriptDuration", "TaskDuration")
TRACE_CATEGORIES = ["devtools.timeline", "blink", "toplevel"]
SVG_SPAN = re.compile(r"<svg\b.*</svg>", re.S)


def _svg_of(html: str) -> etree._Element:
    """The page's inline `<svg>` element, parsed."""
    match = SVG_SPAN.search(html)
    if match is None:
        raise ValueError("no inline <svg> in the page")
    return etree.fromstring(match.group(0).encode("utf-8"))


def _with_svg(html: str, svg: etree._Element | str) -> str:
    """`html` with its inline SVG replaced by `svg` (an element, serialised, or markup as is)."""
    text = svg if isinstance(svg, str) else etree.tostring(svg, encoding="unicode")
    match = SVG_SPAN.search(html)
    assert match is not None
    return html[: match.start()] + text + html[match.end():]


def _elements(svg: etree._Element) -> int:
    """Number of elements in `svg`."""
    return sum(1 for e in svg.iter() if isinstance(e.tag, str))


def _tracks(svg: etree._Element) -> list[etree._Element]:
    """The part tracks (`<g data-part>`)."""
    return [g for g in svg.iter(f"{SVG_NS}g") if g.get("data-part")]


def drop_drawings(svg: etree._Element, keep_every: int = 2) -> etree._Element:
    """Keep every `keep_every`-th drawing of each track's `<defs>`; a frame showing a dropped one shows
    the drawing kept before it (the `<animate>` values rewritten). Returns `svg`, changed."""
    for track in _tracks(svg):
        defs = track.find(f"{SVG_NS}defs")
        kept: dict[str, str] = {}
        last = ""
        for index, drawing in enumerate(list(defs)):
            if index % keep_every == 0:
                last = drawing.get("id")
            else:
                defs.remove(drawing)
            kept[drawing.get("id")] = last
        for animate in track.iter(f"{SVG_NS}animate"):
            values = animate.get("values").split(";")
            animate.set("values", ";".join("#" + kept.get(v[1:], v[1:]) for v in values))
        for use in track.findall(f"{SVG_NS}use"):
            use.set("href", "#" + kept.get(use.get("href")[1:], use.get("href")[1:]))
    return svg


def sets_for_animates(svg: etree._Element) -> etree._Element:
    """Each track's discrete `<animate href>` as one `<set>` per run of equal values. Returns `svg`, changed."""
    for animate in list(svg.iter(f"{SVG_NS}animate")):
        if animate.get("attributeName") != "href":
            continue
        values = animate.get("values").split(";")
        times = [float(t) for t in animate.get("keyTimes").split(";")]
        duration = float(animate.get("dur").rstrip("s"))
        parent = animate.getparent()
        at = parent.index(animate)
        parent.remove(animate)
        for index, (value, time) in enumerate(zip(values, times, strict=True)):
            if index and value == values[index - 1]:
                continue
            step = etree.Element(f"{SVG_NS}set", attributeName="href", to=value, begin=f"{time * duration:.3f}s",
                                 fill="freeze")
            parent.insert(at, step)
            at += 1
    return svg


def attributes_for_classes(svg: etree._Element) -> etree._Element:
    """Every CSS class of the `<style>` written out as presentation attributes on its elements. Returns `svg`."""
    style = svg.find(f"{SVG_NS}style")
    rules = dict(re.findall(r"\.([\w-]+)\{([^}]*)\}", style.text or ""))
    for element in svg.iter():
        names = element.get("class") if isinstance(element.tag, str) else None
        if not names:
            continue
        for name in names.split():
            for declaration in rules.get(name, "").split(";"):
                if ":" in declaration:
                    key, value = declaration.split(":", 1)
                    element.set(key.strip(), value.strip())
        del element.attrib["class"]
    style.text = ""
    return svg


def without_clip_paths(svg: etree._Element) -> etree._Element:
    """`svg` without clipping: each `<clipPath>` becomes a `<defs>` (its outline, which `<use>`s show,
    keeps its id) and the clip-path attributes go. Returns `svg`, changed."""
    for clip in list(svg.iter(f"{SVG_NS}clipPath")):
        clip.tag = f"{SVG_NS}defs"
        del clip.attrib["id"]
    for element in svg.iter():
        if isinstance(element.tag, str) and "clip-path" in element.attrib:
            del element.attrib["clip-path"]
    return svg


def doubled_paths(svg: etree._Element) -> etree._Element:
    """Every path's data written twice (a second, relative subpath: same shape, moved). Returns `svg`."""
    for path in svg.iter(f"{SVG_NS}path"):
        data = path.get("d")
        path.set("d", data + "m0,0" + ("m" + data[1:] if data[:1] in "mM" else data))
    return svg


def page_variants(html: str, written: bytes) -> dict[str, tuple[str, str]]:
    """Variants of the page `html` whose SVG is the document `written` (animation.svg):
    name -> (html, what changed). All but the first two put the SVG in the page as
    render/pages.py does (`inline_svg`: track drawings undisplayed, clip paths hoisted)."""
    def page(svg: etree._Element) -> str:
        return _with_svg(html, str(inline_svg(etree.tostring(svg))))

    def svg_changed(change: Callable[[etree._Element], etree._Element]) -> tuple[str, str]:
        svg = etree.fromstring(written)
        before = _elements(svg), sum(len(p.get("d")) for p in svg.iter(f"{SVG_NS}path"))
        after_svg = change(svg)
        after = _elements(after_svg), sum(len(p.get("d")) for p in after_svg.iter(f"{SVG_NS}path"))
        return page(after_svg), f"elements {after[0] - before[0]:+d}, path data {(after[1] - before[1]) / 1e3:+.0f} KB"

    svg = etree.fromstring(written)
    text = etree.tostring(svg, encoding="unicode")
    made = page(svg)
    variants = {
        "plain page (SVG bytes in a comment)": (_with_svg(html, "<!--" + text.replace("--", "- ") + "-->"), "no SVG"),
        "SVG inline as written (before)": (_with_svg(html, text), f"{_elements(svg)} SVG elements"),
        "as made": (made, "track drawings undisplayed"),
        "no page script": (re.sub(r"<script[^>]*></script>", "", made), "no script"),
        "no audio element": (re.sub(r"<audio\b.*?</audio>", "", made, flags=re.S), "no audio, script ends at once"),
    }
    for name, change in (("half the drawings", drop_drawings), ("<set> runs for <animate href>", sets_for_animates),
                         ("attributes for classes", attributes_for_classes), ("no clip paths", without_clip_paths),
                         ("path data doubled", doubled_paths)):
        variants[name] = svg_changed(change)
    return variants


def load_once(browser, index: Path) -> dict[str, float]:
    """Open `index` in a fresh page; the split of its load (ms) and Chromium's counters (ms)."""
    page = browser.new_page(viewport=VIEWPORT)
    page.add_init_script(READY_PROBE)
    cdp = page.context.new_cdp_session(page)
    cdp.send("Performance.enable")
    page.goto(index.as_uri(), wait_until="load")
    page.wait_for_function("window.__cfReady !== undefined")
    figures = page.evaluate(SPLIT)
    counters = {m["name"]: m["value"] for m in cdp.send("Performance.getMetrics")["metrics"]}
    figures.update({name: counters[name] * 1000 for name in COUNTERS})
    page.close()
    return figures


def playback_cost(browser, index: Path) -> float:
    """Main-thread task time (ms) per second of the inline SVG running on its own (no audio) on `index`."""
    page = browser.new_page(viewport=VIEWPORT)
    cdp = page.context.new_cdp_session(page)
    cdp.send("Performance.enable")
    page.goto(index.as_uri(), wait_until="load")
    page.wait_for_timeout(300)

    def task() -> float:
        return next(m["value"] for m in cdp.send("Performance.getMetrics")["metrics"] if m["name"] == "TaskDuration")

    before = task()
    page.evaluate("document.getElementById('cf-face') && document.getElementById('cf-face').unpauseAnimations()")
    page.wait_for_timeout(PLAY_SECONDS * 1000)
    cost = (task() - before) * 1000 / PLAY_SECONDS
    page.close()
    return cost


def _main_thread(trace: Path) -> list[dict]:
    """The complete events of the renderer's main thread in the Chromium trace file `trace`."""
    events = json.loads(trace.read_text(encoding="utf-8"))
    events = events["traceEvents"] if isinstance(events, dict) else events
    main = {(e["pid"], e["tid"]) for e in events
            if e.get("name") == "thread_name" and e["args"].get("name") == "CrRendererMain"}
    return [e for e in events if (e["pid"], e["tid"]) in main and e.get("ph") == "X"]


def thread_ms(events: list[dict], name: str | None = None) -> float:
    """Thread (CPU) time in ms of the events called `name`, or of the outermost events (None)."""
    if name is not None:
        return sum(e.get("tdur", 0) for e in events if e["name"] == name) / 1000
    total, end = 0, -1
    for event in sorted(events, key=lambda e: (e["ts"], -e.get("dur", 0))):
        if event["ts"] >= end:
            total, end = total + event.get("tdur", 0), event["ts"] + event.get("dur", 0)
    return total / 1000


def cpu_once(browser, index: Path, trace: Path) -> dict[str, float]:
    """Open `index` in a fresh page under a trace: the main thread's CPU ms to ready and of its style
    updates, then of playing (the SVG on its own, no audio) per second."""
    page = browser.new_page(viewport=VIEWPORT)
    page.add_init_script(READY_PROBE)
    browser.start_tracing(page=page, path=str(trace), categories=TRACE_CATEGORIES)
    page.goto(index.as_uri(), wait_until="load")
    page.wait_for_function("window.__cfReady !== undefined")
    browser.stop_tracing()
    events = _main_thread(trace)
    figures = {"cpu": thread_ms(events), "style cpu": thread_ms(events, "UpdateLayoutTree")}
    page.evaluate("() => { const audio = document.getElementById('cf-audio'); if (audio) audio.pause(); }")
    page.wait_for_timeout(300)
    browser.start_tracing(page=page, path=str(trace), categories=TRACE_CATEGORIES)
    page.evaluate("document.getElementById('cf-face') && document.getElementById('cf-face').unpauseAnimations()")
    page.wait_for_timeout(PLAY_SECONDS * 1000)
    browser.stop_tracing()
    figures["playing cpu"] = thread_ms(_main_thread(trace)) / PLAY_SECONDS
    page.close()
    return figures


def measure(folder: Path, work: Path) -> None:
    """Write the variants of `folder`'s index.html beside copies of its files under `work`, load each
    RUNS times (interleaved) and print one table row per variant."""
    from playwright.sync_api import sync_playwright

    html = (folder / "index.html").read_text(encoding="utf-8")
    pages: dict[str, tuple[Path, str, int]] = {}
    variants = page_variants(html, (folder / "animation.svg").read_bytes())
    for number, (name, (text, change)) in enumerate(variants.items()):
        target = work / f"v{number}"
        shutil.copytree(folder, target, ignore=shutil.ignore_patterns("animation.svg", "*.TextGrid"))
        (target / "index.html").write_text(text, encoding="utf-8")
        pages[name] = (target / "index.html", change, len(text.encode("utf-8")))
    runs: dict[str, list[dict[str, float]]] = {name: [] for name in pages}
    with sync_playwright() as play:
        browser = play.chromium.launch(executable_path="/usr/bin/chromium", headless=True, args=CHROMIUM_ARGS)
        for _ in range(RUNS):
            for name, (index, _, _) in pages.items():
                runs[name].append(load_once(browser, index))
        playing = {name: statistics.median(playback_cost(browser, pages[name][0]) for _ in range(3))
                   for name in ("as made", "half the drawings", "<set> runs for <animate href>",
                                "attributes for classes", "no clip paths", "path data doubled",
                                 "SVG inline as written (before)")}
        browser.close()
    plain = statistics.median(r["ready"] for r in runs["plain page (SVG bytes in a comment)"])
    print(f"{folder.name}: median of {RUNS} (ms); ready/plain = ratio to the plain page of the same size")
    print("| variant | change | bytes | ready | /plain | parse | parse->load | first paint | style | layout "
          "| script | tasks | playing (ms/s) |")
    print("| --- " * 13 + "|")
    for name, (_, change, size) in pages.items():
        med = {key: statistics.median(r[key] for r in runs[name]) for key in runs[name][0]}
        play_cost = f"{playing[name]:.0f}" if name in playing else ""
        print(f"| {name} | {change} | {size / 1e6:.2f} MB | {med['ready']:.0f} | {med['ready'] / plain:.2f} "
              f"| {med['parse']:.0f} | {med['load']:.0f} | {med['paint']:.0f} | {med['RecalcStyleDuration']:.0f} "
              f"| {med['LayoutDuration']:.0f} | {med['ScriptDuration']:.0f} | {med['TaskDuration']:.0f} | {play_cost} |")
    sys.stdout.flush()


def element_kinds(svg_file: Path) -> Counter[str]:
    """How many elements of each kind (tag without namespace) the SVG file `svg_file` holds."""
    root = etree.parse(str(svg_file), etree.XMLParser(huge_tree=True)).getroot()
    return Counter(etree.QName(node).localname for node in root.iter() if isinstance(node.tag, str))


def instantiated(svg: etree._Element) -> tuple[int, int]:
    """The elements of `svg` and the clones Chromium makes for its `<use>`s: every `<use>` in the
    document, displayed or not, holds a clone of its target, whose own `<use>`s hold clones in turn."""
    ids = {node.get("id"): node for node in svg.iter() if isinstance(node.tag, str) and node.get("id")}
    nodes = [node for node in svg.iter() if isinstance(node.tag, str)]  # keeps the proxies (and id()s) alive
    sizes: dict[int, int] = {}

    def size(node: etree._Element) -> int:
        """Elements of `node`'s subtree with the clones of the `<use>`s in it."""
        if id(node) not in sizes:
            target = ids.get((node.get("href") or "")[1:]) if node.tag == f"{SVG_NS}use" else None
            sizes[id(node)] = (1 + sum(size(child) for child in node if isinstance(child.tag, str))
                               + (size(target) if target is not None else 0))
        return sizes[id(node)]

    return len(nodes), size(svg) - len(nodes)


def compare(pairs: list[tuple[Path, Path]]) -> None:
    """For each (before, after) pair of page folders of one recording: the elements per kind per
    minute of their animation.svg, and page ready, parse, style and playback of their index.html,
    loaded RUNS times interleaved (medians, ms), then their main thread's CPU (cpu_once, RUNS times
    interleaved)."""
    from playwright.sync_api import sync_playwright

    for before, after in pairs:
        end = re.search(r"xmax = ([\d.]+)", (before / "alignment.TextGrid").read_text(encoding="utf-8"))
        if end is None:
            raise ValueError(f"{before / 'alignment.TextGrid'}: no xmax (the recording's length)")
        minutes = float(end.group(1)) / 60
        kinds = [element_kinds(folder / "animation.svg") for folder in (before, after)]
        print(f"{before} -> {after}: elements per minute of the {minutes:.2f} min recording (all: "
              f"{sum(kinds[0].values()):,} -> {sum(kinds[1].values()):,})")
        for kind, _ in kinds[0].most_common(8):
            print(f"| {kind} | {kinds[0][kind] / minutes:,.0f} | {kinds[1][kind] / minutes:,.0f} |")
        built = [instantiated(_svg_of((folder / "index.html").read_text(encoding="utf-8"))) for folder in (before, after)]
        print("the pages' inline SVG: elements + clones of <use> targets: "
              + " -> ".join(f"{own:,} + {clones:,} = {own + clones:,}" for own, clones in built))
    loads: dict[Path, list[dict[str, float]]] = {folder: [] for pair in pairs for folder in pair}
    with sync_playwright() as play:
        browser = play.chromium.launch(executable_path="/usr/bin/chromium", headless=True, args=CHROMIUM_ARGS)
        for _ in range(RUNS):
            for folder in loads:
                loads[folder].append(load_once(browser, folder / "index.html"))
        playing = {folder: statistics.median(playback_cost(browser, folder / "index.html") for _ in range(3))
                   for folder in loads}
        cpus: dict[Path, list[dict[str, float]]] = {folder: [] for folder in loads}
        with tempfile.TemporaryDirectory(prefix="cartoonface-trace-") as tmp:
            for _ in range(RUNS):
                for folder in loads:
                    cpus[folder].append(cpu_once(browser, folder / "index.html", Path(tmp) / "trace.json"))
        browser.close()
    for folder, runs in loads.items():
        med = {key: statistics.median(r[key] for r in runs) for key in runs[0]}
        cpu = {key: statistics.median(r[key] for r in cpus[folder]) for key in cpus[folder][0]}
        print(f"{folder}: ready {med['ready']:.0f} parse {med['parse']:.0f} style {med['RecalcStyleDuration']:.0f} "
              f"layout {med['LayoutDuration']:.0f} playing {playing[folder]:.0f} ms/s; main thread CPU: to ready "
              f"{cpu['cpu']:.0f} style {cpu['style cpu']:.0f} playing {cpu['playing cpu']:.0f} ms/s")


def main(folders: list[Path] | None = None) -> None:
    """Measure `folders` (default: the audio-book and announcer pages of bench/generate.py's input)."""
    with tempfile.TemporaryDirectory(prefix="cartoonface-page-") as tmp:
        work = Path(tmp)
        if not folders:
            from cartoonface.data import SAMPLE_FACES
            from cartoonface.pipeline import Options, generate

            audio, transcript, seconds = build_input(work)
            face = sorted(SAMPLE_FACES.glob("*.json"))[0]
            print(f"input: {seconds:.1f} s of THCHS-30 speech, face {face.name}")
            folders = [generate(face, audio, transcript, work / page, Options(page=page)).out_dir
                       for page in ("audiobook", "announcer")]
        for number, folder in enumerate(folders):
            measure(folder, work / f"m{number}")


if __name__ == "__main__":
    if sys.argv[1:2] == ["--compare"]:  # --compare BEFORE AFTER [BEFORE AFTER ...]
        folders = [Path(arg) for arg in sys.argv[2:]]
        compare(list(zip(folders[::2], folders[1::2], strict=True)))
    else:
        main([Path(arg) for arg in sys.argv[1:]] or None)
