/* Photo editor: drag the detected points over the photo (mouse, pen or touch through
 * pointer events; arrow keys move the selected point, Shift moves further). A touch takes
 * the nearest point within GRAB_PX (a 44 px target, whatever the dot's size); a touch with
 * no point near pans the zoomed photo, two fingers pinch-zoom it, and the zoom buttons (or
 * Ctrl + wheel) zoom around the selected point. Zooming changes the SVG's viewBox, so the
 * dots keep DOT_PX on screen and spread apart.
 * After a change the points are sent to the server (debounced), which answers with the new
 * cartoon preview (SVG, shown as an image) and warnings about points somewhere impossible
 * (shown next to the point and listed above the photo), or the reason they cannot make a
 * face. The hidden field #points always holds the points, so "Use this face" saves them;
 * "Back to the detected points" (shown only with this script) undoes every move. */
(function () {
  "use strict";
  var editor = document.getElementById("editor");
  var svg = document.getElementById("overlay");
  if (!editor || !svg) return;
  var url = editor.getAttribute("data-preview-url");
  var field = document.getElementById("points");
  var form = document.getElementById("use-form");
  var token = form.querySelector("input[name=csrf_token]").value;
  var preview = document.getElementById("preview");
  var previewState = document.getElementById("preview-state");
  var error = document.getElementById("points-error");
  var nameBox = document.getElementById("point-name");
  var stage = document.getElementById("stage");
  var tip = document.getElementById("point-tip");
  var warningBox = document.getElementById("point-warnings");
  var warningLead = document.getElementById("point-warnings-lead");
  var warningList = document.getElementById("point-warning-list");
  var zoomLevel = document.getElementById("zoom-level");
  var circles = Array.prototype.slice.call(svg.querySelectorAll("circle.point"));
  var initial = svg.viewBox.baseVal;
  var photo = { x: initial.x, y: initial.y, width: initial.width, height: initial.height };
  var DEBOUNCE_MS = 250;
  var GRAB_PX = 22;    // a touch this close (CSS pixels) to a point takes it: a 44 px target
  var DOT_PX = 5;      // a point's radius on screen (CSS pixels), at any zoom
  var SELECTED_PX = 8; // the selected or dragged point's radius on screen
  var ZOOM_STEP = 1.5;
  var MAX_ZOOM = 8;
  var timer = null;
  var sent = 0;      // number of the last request sent
  var shownReq = 0;  // number of the last answer shown (older answers are dropped)
  var drag = null;   // {circle, pointerId, dx, dy} or {pan: true, pointerId, x, y}
  var pointers = {}; // pointerId -> {x, y} of the pointers down on the photo
  var pinch = null;  // {distance, zoom} when two pointers pinch
  var selected = null;
  var warnings = {}; // point name -> message
  var view = { zoom: 1, cx: photo.x + photo.width / 2, cy: photo.y + photo.height / 2 };

  function clamp(value, low, high) { return Math.min(high, Math.max(low, value)); }

  function svgPoint(event) {
    var matrix = svg.getScreenCTM().inverse();
    var p = new DOMPoint(event.clientX, event.clientY).matrixTransform(matrix);
    return { x: p.x, y: p.y };
  }

  // Photo pixels per CSS pixel at the present zoom.
  function unit() {
    var width = svg.getBoundingClientRect().width;
    return width > 0 ? photo.width / view.zoom / width : 1;
  }

  function sizeDots() {
    var k = unit();
    circles.forEach(function (c) {
      var big = c === selected || (drag && drag.circle === c);
      c.setAttribute("r", ((big ? SELECTED_PX : DOT_PX) * k).toFixed(2));
    });
    placeTip();
  }

  function applyView() {
    var width = photo.width / view.zoom;
    var height = photo.height / view.zoom;
    view.cx = clamp(view.cx, photo.x + width / 2, photo.x + photo.width - width / 2);
    view.cy = clamp(view.cy, photo.y + height / 2, photo.y + photo.height - height / 2);
    svg.setAttribute("viewBox", [view.cx - width / 2, view.cy - height / 2, width, height]
      .map(function (v) { return v.toFixed(2); }).join(" "));
    zoomLevel.textContent = (Math.round(view.zoom * 10) / 10) + "×";
    editor.setAttribute("data-zoom", String(view.zoom));
    sizeDots();
  }

  // Zoom to `zoom`, keeping the photo point (x, y) where it is on screen.
  function zoomTo(zoom, x, y) {
    var next = clamp(zoom, 1, MAX_ZOOM);
    var k = view.zoom / next;
    view.cx = x + (view.cx - x) * k;
    view.cy = y + (view.cy - y) * k;
    view.zoom = next;
    applyView();
  }

  function focusPoint() {
    if (selected) return { x: parseFloat(selected.getAttribute("cx")), y: parseFloat(selected.getAttribute("cy")) };
    return { x: view.cx, y: view.cy };
  }

  function place(circle, x, y) {
    circle.setAttribute("cx", clamp(x, photo.x, photo.x + photo.width).toFixed(2));
    circle.setAttribute("cy", clamp(y, photo.y, photo.y + photo.height).toFixed(2));
  }

  function points() {
    var out = {};
    circles.forEach(function (c) {
      out[c.getAttribute("data-name")] = [parseFloat(c.getAttribute("cx")), parseFloat(c.getAttribute("cy"))];
    });
    return out;
  }

  // The warning bubble beside the selected point when it has a warning, else beside the
  // first point that has one.
  function placeTip() {
    var circle = selected && warnings[selected.getAttribute("data-name")] ? selected : null;
    if (!circle) {
      circle = circles.filter(function (c) { return warnings[c.getAttribute("data-name")]; })[0] || null;
    }
    if (!circle) { tip.hidden = true; return; }
    var box = stage.getBoundingClientRect();
    var dot = circle.getBoundingClientRect();
    var x = dot.left + dot.width / 2 - box.left;
    var y = dot.top + dot.height / 2 - box.top;
    tip.textContent = "⚠ " + warnings[circle.getAttribute("data-name")];
    tip.hidden = !(x >= 0 && y >= 0 && x <= box.width && y <= box.height);
    tip.classList.toggle("left", x > box.width / 2);
    tip.classList.toggle("up", y > box.height * 0.6);
    tip.style.left = (x > box.width / 2 ? x - 14 : x + 14) + "px";
    tip.style.top = y + "px";
  }

  function showWarnings(list) {
    warnings = {};
    list.forEach(function (w) { warnings[w.point] = w.message; });
    circles.forEach(function (c) { c.classList.toggle("warn", Boolean(warnings[c.getAttribute("data-name")])); });
    warningList.textContent = "";
    list.forEach(function (w) {
      var li = document.createElement("li");
      li.setAttribute("data-point", w.point);
      li.textContent = w.message;
      warningList.appendChild(li);
    });
    if (list.length) warningLead.textContent = "Some points are where no face has them:";
    warningBox.hidden = list.length === 0;
    placeTip();
  }

  function select(circle) {
    if (selected) selected.classList.remove("selected");
    selected = circle;
    if (circle) {
      circle.classList.add("selected");
      nameBox.textContent = circle.getAttribute("data-name") + ": " + circle.getAttribute("data-label");
    }
    sizeDots();
  }

  function send() {
    timer = null;
    var number = ++sent;
    var body = new URLSearchParams();
    body.set("csrf_token", token);
    body.set("points", field.value);
    previewState.textContent = "Updating the cartoon…";
    fetch(url, { method: "POST", body: body, credentials: "same-origin", cache: "no-store" })
      .then(function (response) {
        if (response.status === 404) {
          return { ok: false, answer: { error: "This photo is no longer kept (photos are kept for a day); please upload it again." } };
        }
        return response.json().then(function (answer) { return { ok: response.ok, answer: answer }; });
      })
      .then(function (result) {
        if (number < shownReq) return;
        shownReq = number;
        if (result.ok) {
          preview.src = "data:image/svg+xml;charset=utf-8," + encodeURIComponent(result.answer.svg);
          error.hidden = true;
          error.textContent = "";
          previewState.textContent = "Cartoon from these points";
          showWarnings(result.answer.warnings || []);
          editor.setAttribute("data-updated", String(number));
        } else {
          error.textContent = result.answer.error || "These points do not make a face.";
          error.hidden = false;
          previewState.textContent = "The cartoon shows the last points that made a face";
        }
      })
      .catch(function () {
        previewState.textContent = "Could not reach the server; the cartoon is not up to date";
      });
  }

  function changed() {
    field.value = JSON.stringify(points());
    placeTip();
    if (timer !== null) window.clearTimeout(timer);
    timer = window.setTimeout(send, DEBOUNCE_MS);
  }

  function nearest(event) {
    var best = null;
    var bestDistance = GRAB_PX;
    circles.forEach(function (c) {
      var r = c.getBoundingClientRect();
      var d = Math.hypot(event.clientX - (r.left + r.width / 2), event.clientY - (r.top + r.height / 2));
      if (d < bestDistance) { best = c; bestDistance = d; }
    });
    return best;
  }

  function pointerCount() { return Object.keys(pointers).length; }

  function startPinch() {
    var ids = Object.keys(pointers);
    var a = pointers[ids[0]];
    var b = pointers[ids[1]];
    if (drag && drag.circle) drag.circle.classList.remove("dragging");
    drag = null;
    pinch = { distance: Math.max(Math.hypot(a.x - b.x, a.y - b.y), 1), zoom: view.zoom };
  }

  svg.addEventListener("pointerdown", function (event) {
    pointers[event.pointerId] = { x: event.clientX, y: event.clientY };
    svg.setPointerCapture(event.pointerId);
    event.preventDefault();
    if (pointerCount() === 2) { startPinch(); return; }
    if (pointerCount() > 2 || drag) return;
    var circle = nearest(event);
    var at = svgPoint(event);
    if (!circle) {
      drag = { pan: true, pointerId: event.pointerId, x: event.clientX, y: event.clientY };
      return;
    }
    drag = { circle: circle, pointerId: event.pointerId,
             dx: parseFloat(circle.getAttribute("cx")) - at.x, dy: parseFloat(circle.getAttribute("cy")) - at.y };
    circle.classList.add("dragging");
    select(circle);
    circle.focus({ preventScroll: true });
  });

  svg.addEventListener("pointermove", function (event) {
    if (!pointers[event.pointerId]) return;
    pointers[event.pointerId] = { x: event.clientX, y: event.clientY };
    event.preventDefault();
    if (pinch && pointerCount() === 2) {
      var ids = Object.keys(pointers);
      var a = pointers[ids[0]];
      var b = pointers[ids[1]];
      var middle = svgPoint({ clientX: (a.x + b.x) / 2, clientY: (a.y + b.y) / 2 });
      zoomTo(pinch.zoom * Math.hypot(a.x - b.x, a.y - b.y) / pinch.distance, middle.x, middle.y);
      return;
    }
    if (!drag || event.pointerId !== drag.pointerId) return;
    if (drag.pan) {
      var k = unit();
      view.cx -= (event.clientX - drag.x) * k;
      view.cy -= (event.clientY - drag.y) * k;
      drag.x = event.clientX;
      drag.y = event.clientY;
      applyView();
      return;
    }
    var at = svgPoint(event);
    place(drag.circle, at.x + drag.dx, at.y + drag.dy);
    changed();
  });

  function endPointer(event) {
    delete pointers[event.pointerId];
    if (pointerCount() < 2) pinch = null;
    if (!drag || event.pointerId !== drag.pointerId) return;
    if (drag.circle) drag.circle.classList.remove("dragging");
    drag = null;
    sizeDots();
  }
  svg.addEventListener("pointerup", endPointer);
  svg.addEventListener("pointercancel", endPointer);

  svg.addEventListener("wheel", function (event) {
    if (!event.ctrlKey) return; // a plain wheel scrolls the page; Ctrl + wheel (and a trackpad pinch) zooms
    event.preventDefault();
    var at = svgPoint(event);
    zoomTo(view.zoom * Math.exp(-event.deltaY / 300), at.x, at.y);
  }, { passive: false });

  document.getElementById("zoom-in").addEventListener("click", function () {
    var at = focusPoint();
    zoomTo(view.zoom * ZOOM_STEP, at.x, at.y);
    if (selected) { view.cx = at.x; view.cy = at.y; applyView(); }
  });
  document.getElementById("zoom-out").addEventListener("click", function () {
    var at = focusPoint();
    zoomTo(view.zoom / ZOOM_STEP, at.x, at.y);
  });
  document.getElementById("zoom-fit").addEventListener("click", function () { zoomTo(1, view.cx, view.cy); });
  document.getElementById("zoom-bar").hidden = false;

  circles.forEach(function (circle) {
    circle.addEventListener("focus", function () { select(circle); });
    circle.addEventListener("pointerenter", function () {
      nameBox.textContent = circle.getAttribute("data-name") + ": " + circle.getAttribute("data-label");
    });
    circle.addEventListener("keydown", function (event) {
      var step = (event.shiftKey ? 5 : 1) * photo.width / 512 / view.zoom;
      var moves = { ArrowLeft: [-step, 0], ArrowRight: [step, 0], ArrowUp: [0, -step], ArrowDown: [0, step] };
      var move = moves[event.key];
      if (!move) return;
      event.preventDefault();
      place(circle, parseFloat(circle.getAttribute("cx")) + move[0], parseFloat(circle.getAttribute("cy")) + move[1]);
      changed();
    });
  });

  var reset = document.getElementById("reset-points");
  reset.hidden = false;
  reset.addEventListener("click", function () {
    var detected = JSON.parse(reset.getAttribute("data-points"));
    circles.forEach(function (c) {
      var p = detected[c.getAttribute("data-name")];
      place(c, p[0], p[1]);
    });
    changed();
  });

  form.addEventListener("submit", function () {
    field.value = JSON.stringify(points());
  });

  Array.prototype.slice.call(warningList.querySelectorAll("li")).forEach(function (li) {
    warnings[li.getAttribute("data-point")] = li.textContent;
  });
  window.addEventListener("resize", sizeDots);
  applyView();
})();
