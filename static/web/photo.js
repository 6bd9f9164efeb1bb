/* Photo editor: drag the detected points over the photo (mouse, pen or touch through
 * pointer events; arrow keys move the selected point, Shift moves further). After a
 * change the points are sent to the server (debounced), which answers with the new
 * cartoon preview (SVG, shown as an image) or the reason they cannot make a face.
 * The hidden field #points always holds the points, so "Use this face" saves them;
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
  var circles = Array.prototype.slice.call(svg.querySelectorAll("circle.point"));
  var box = svg.viewBox.baseVal;
  var DEBOUNCE_MS = 250;
  var GRAB_PX = 24; // a touch this close (CSS pixels) to a point takes it
  var timer = null;
  var sent = 0;      // number of the last request sent
  var shownReq = 0;  // number of the last answer shown (older answers are dropped)
  var drag = null;   // {circle, pointerId, dx, dy}
  var selected = null;

  function svgPoint(event) {
    var matrix = svg.getScreenCTM().inverse();
    var p = new DOMPoint(event.clientX, event.clientY).matrixTransform(matrix);
    return { x: p.x, y: p.y };
  }

  function clamp(value, low, high) { return Math.min(high, Math.max(low, value)); }

  function place(circle, x, y) {
    circle.setAttribute("cx", clamp(x, box.x, box.x + box.width).toFixed(2));
    circle.setAttribute("cy", clamp(y, box.y, box.y + box.height).toFixed(2));
  }

  function points() {
    var out = {};
    circles.forEach(function (c) {
      out[c.getAttribute("data-name")] = [parseFloat(c.getAttribute("cx")), parseFloat(c.getAttribute("cy"))];
    });
    return out;
  }

  function select(circle) {
    if (selected) selected.classList.remove("selected");
    selected = circle;
    if (circle) {
      circle.classList.add("selected");
      nameBox.textContent = circle.getAttribute("data-name") + ": " + circle.getAttribute("data-label");
    }
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

  svg.addEventListener("pointerdown", function (event) {
    if (drag) return;
    var circle = event.target.classList && event.target.classList.contains("point") ? event.target : nearest(event);
    if (!circle) return;
    event.preventDefault();
    var at = svgPoint(event);
    drag = { circle: circle, pointerId: event.pointerId,
             dx: parseFloat(circle.getAttribute("cx")) - at.x, dy: parseFloat(circle.getAttribute("cy")) - at.y };
    svg.setPointerCapture(event.pointerId);
    circle.classList.add("dragging");
    select(circle);
    circle.focus({ preventScroll: true });
  });

  svg.addEventListener("pointermove", function (event) {
    if (!drag || event.pointerId !== drag.pointerId) return;
    event.preventDefault();
    var at = svgPoint(event);
    place(drag.circle, at.x + drag.dx, at.y + drag.dy);
    changed();
  });

  function endDrag(event) {
    if (!drag || event.pointerId !== drag.pointerId) return;
    drag.circle.classList.remove("dragging");
    drag = null;
  }
  svg.addEventListener("pointerup", endDrag);
  svg.addEventListener("pointercancel", endDrag);

  circles.forEach(function (circle) {
    circle.addEventListener("focus", function () { select(circle); });
    circle.addEventListener("pointerenter", function () {
      nameBox.textContent = circle.getAttribute("data-name") + ": " + circle.getAttribute("data-label");
    });
    circle.addEventListener("keydown", function (event) {
      var step = (event.shiftKey ? 5 : 1) * box.width / 512;
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
})();
