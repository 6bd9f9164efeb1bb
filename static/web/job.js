/* Job page: poll the job's status (JSON) twice a second, move the progress bar, tick the
 * stages passed, and reload the page when the job is done or failed (the server then
 * renders the result or the error); stop when the job is gone. */
(function () {
  "use strict";
  var box = document.getElementById("job");
  if (!box) return;
  var url = box.getAttribute("data-status-url");
  var bar = document.getElementById("progress");
  var percent = document.getElementById("percent");
  var stage = document.getElementById("stage");

  var steps = Array.prototype.slice.call(document.querySelectorAll("#stages li"));

  // Mark the stages before the current one done and the current one current (every stage
  // shows in the list, however short it was).
  function markStages(current) {
    var at = -1;
    steps.forEach(function (li, index) { if (li.getAttribute("data-stage") === current) at = index; });
    steps.forEach(function (li, index) {
      li.className = index < at ? "done" : index === at ? "current" : "";
      if (index === at) li.setAttribute("aria-current", "step"); else li.removeAttribute("aria-current");
    });
  }

  function show(status) {
    bar.value = status.percent;
    bar.textContent = status.percent + "%";
    percent.textContent = status.percent + "%";
    stage.textContent = status.stage_label;
    box.setAttribute("data-state", status.state);
    markStages(status.stage);
  }

  function poll() {
    fetch(url, { cache: "no-store", credentials: "same-origin" })
      .then(function (response) {
        if (response.status === 404) return { state: "gone" };
        if (!response.ok) throw new Error("status " + response.status);
        return response.json();
      })
      .then(function (status) {
        if (status.state === "gone") {
          var error = document.getElementById("job-error");
          error.textContent = "This job no longer exists (removed by the retention limit).";
          error.hidden = false;
          return;
        }
        show(status);
        if (status.state === "done" || status.state === "failed") {
          window.setTimeout(function () { window.location.reload(); }, 400);
        } else {
          window.setTimeout(poll, 500);
        }
      })
      .catch(function () { window.setTimeout(poll, 2000); });
  }

  poll();
})();
