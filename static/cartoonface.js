/* cartoonface page clock (docs/output.md).
 *
 * The page's <audio id="cf-audio"> is the only clock. This script keeps the
 * SMIL document time of the inline <svg id="cf-face"> on audio.currentTime
 * through play, pause, seeking, playback-rate changes and tab switches:
 * - at rate 1 the SVG runs on its own (unpauseAnimations) and is put back
 *   (setCurrentTime) whenever it drifts more than half a frame from the audio;
 * - at any other rate the SVG stays paused and is moved to the audio time
 *   on every animation frame;
 * - while the audio waits for data (from "play" to "playing", buffering) or
 *   is paused, or the tab is hidden, the SVG stays paused at the audio time.
 * It also highlights the sentence being spoken ([data-start], [data-end] in
 * seconds), writes it into [data-caption], seeks when a sentence is clicked,
 * and lets Space toggle play.
 */
(function () {
  "use strict";
  var audio = document.getElementById("cf-audio");
  var svg = document.getElementById("cf-face");
  if (!audio || !svg || typeof svg.setCurrentTime !== "function") return;

  var fps = parseFloat(audio.getAttribute("data-fps")) || 30;
  var tolerance = 0.5 / fps; // seconds: half a frame
  var sentences = Array.prototype.slice.call(document.querySelectorAll(".cf-sentence[data-start]"));
  // Read once: the highlight runs on every animation frame.
  var starts = sentences.map(function (s) { return parseFloat(s.getAttribute("data-start")); });
  var ends = sentences.map(function (s) { return parseFloat(s.getAttribute("data-end")); });
  var caption = document.querySelector("[data-caption]");
  var current = null;
  var ticking = false;
  var waiting = false;

  function running() {
    return !audio.paused && !audio.ended && !waiting && !document.hidden;
  }

  function freeRunning() {
    return running() && audio.playbackRate === 1;
  }

  // The sentence spoken at t seconds (the sentences come in time order), or null.
  function spokenAt(t) {
    var low = 0, high = starts.length - 1, last = -1;
    while (low <= high) {
      var middle = (low + high) >> 1;
      if (starts[middle] <= t) {
        last = middle;
        low = middle + 1;
      } else {
        high = middle - 1;
      }
    }
    return last >= 0 && t < ends[last] ? sentences[last] : null;
  }

  function highlight(t) {
    var found = spokenAt(t);
    if (found === current) return;
    if (current) {
      current.classList.remove("cf-speaking");
      current.removeAttribute("aria-current");
    }
    current = found;
    if (current) {
      current.classList.add("cf-speaking");
      current.setAttribute("aria-current", "true");
    }
    if (caption) caption.textContent = current ? current.textContent : "";
  }

  function sync(force) {
    var t = audio.currentTime;
    if (force || Math.abs(svg.getCurrentTime() - t) > tolerance) svg.setCurrentTime(t);
    highlight(t);
  }

  function tick() {
    if (!running()) {
      ticking = false;
      return;
    }
    sync(!freeRunning());
    window.requestAnimationFrame(tick);
  }

  function follow() {
    if (freeRunning()) svg.unpauseAnimations();
    else svg.pauseAnimations();
    sync(true);
    if (running() && !ticking) {
      ticking = true;
      window.requestAnimationFrame(tick);
    }
  }

  // Between "play" and "playing" (and while buffering) the audio clock stands still: so does the face.
  ["play", "waiting"].forEach(function (name) {
    audio.addEventListener(name, function () { waiting = true; follow(); });
  });
  audio.addEventListener("playing", function () { waiting = false; follow(); });
  ["pause", "seeking", "seeked", "ratechange", "ended", "timeupdate", "loadedmetadata"].forEach(function (name) {
    audio.addEventListener(name, name === "timeupdate" ? function () { if (!running()) sync(false); } : follow);
  });
  document.addEventListener("visibilitychange", follow);

  // One listener for every sentence (a long book has thousands).
  document.addEventListener("click", function (event) {
    var s = event.target && event.target.closest ? event.target.closest(".cf-sentence[data-start]") : null;
    if (s) audio.currentTime = starts[sentences.indexOf(s)];
  });

  document.addEventListener("keydown", function (event) {
    if (event.key !== " " && event.code !== "Space") return;
    var target = event.target;
    if (target === audio || (target && target.closest && target.closest("input, textarea, select, button, a, [contenteditable]"))) return;
    event.preventDefault();
    if (audio.paused) {
      var started = audio.play();
      if (started && started.catch) started.catch(function () {});
    } else {
      audio.pause();
    }
  });

  svg.pauseAnimations();
  sync(true);
})();
