/* What prima show's page and prima live's page draw alike: a trace line's words, the
   trace table's rows, poses between samples, the bubbles on the map, the robot's and
   the user's markers. Words are set as text (textContent), never read as markup. */
const PrimaDraw = (function () {
  "use strict";

  function esc(text) {  // for the few places that build markup (the details panel)
    return String(text).replace(/[&<>"]/g, function (c) {
      return {"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;"}[c];
    });
  }

  // Plotly reads a few tags and entities in its texts (&lt; and the like, not &quot;)
  function plotlyText(text) {
    return String(text).replace(/[&<>]/g, function (c) {
      return {"&": "&amp;", "<": "&lt;", ">": "&gt;"}[c];
    });
  }

  function what(row) {  // a line as the trace table says it
    if (row.kind === "user") {
      return row.action === "say" ? '"' + (row.text || "") + '"' : row.action +
        (row.detail && row.detail.target ? " " + row.detail.target : "");
    }
    const parts = [];
    if (row.command) parts.push(row.command);
    if (row.text) parts.push(row.command ? '"' + row.text + '"' : row.text);
    if (row.detail && row.detail.args) parts.push(row.detail.args);
    if (row.kind === "end" && row.detail) {  // why a Command got nowhere, where it did
      if (row.detail.error) parts.push("(failed: " + row.detail.error + ")");
      else if (/(^|, )blocked=True(,|$)/.test(row.detail.result || "")) {
        parts.push("(blocked: something in the way; it tries again)");
      }
    }
    if (!parts.length && row.detail) parts.push(JSON.stringify(row.detail));
    return parts.join(" ");
  }

  function tableRow(row, i) {  // numbered by the line's seq, as jsonl, judge and debug number it
    const tr = document.createElement("tr");
    tr.dataset.i = i;
    [row.seq == null ? i : row.seq, row.t.toFixed(2), row.kind, row.app || "",
     row.ab == null ? "" : row.ab, what(row), row.reason || ""].forEach(function (cell) {
      const td = document.createElement("td");
      td.textContent = String(cell);
      tr.appendChild(td);
    });
    return tr;
  }

  function poseAt(poses, t) {  // [t, x, y, heading], interpolated between samples
    if (!poses.length) return null;
    let lo = 0, hi = poses.length - 1;
    if (t <= poses[0][0]) return poses[0];
    if (t >= poses[hi][0]) return poses[hi];
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (poses[mid][0] <= t) lo = mid; else hi = mid;
    }
    const a = poses[lo], b = poses[hi];
    const f = b[0] > a[0] ? (t - a[0]) / (b[0] - a[0]) : 1;
    const turn = ((b[3] - a[3]) % 360 + 540) % 360 - 180;
    return [t, a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2]), a[3] + f * turn];
  }

  function angle(heading) {  // Plotly's marker angle (clockwise from up) for a heading
    return (90 - heading + 360) % 360;
  }

  // Words (or an action) beside the robot or the user: the n-th of theirs shown, above
  // its marker, or below it.
  function bubble(who, pose, text, n, below) {
    return {x: pose[1], y: pose[2], text: plotlyText(String(text).slice(0, 80)), showarrow: true,
            arrowhead: 0, ax: who === "robot" ? -40 : 40, ay: (below ? 1 : -1) * (30 + 22 * n),
            bgcolor: who === "robot" ? "#ecf0f1" : "#fdebd0",
            bordercolor: who === "robot" ? "#2c3e50" : "#e67e22",
            borderpad: 3, font: {size: 11}};
  }

  function markers(mapDiv, robot, user, robotTrace, userTrace) {  // move both markers
    const xs = [], ys = [], angles = [], idx = [];
    [[robot, robotTrace], [user, userTrace]].forEach(function (p) {
      if (!p[0]) return;
      xs.push([p[0][1]]); ys.push([p[0][2]]); angles.push(angle(p[0][3]));
      idx.push(p[1]);
    });
    if (idx.length) Plotly.restyle(mapDiv, {x: xs, y: ys, "marker.angle": angles}, idx);
  }

  return {esc: esc, plotlyText: plotlyText, what: what, tableRow: tableRow, poseAt: poseAt,
          angle: angle, bubble: bubble, markers: markers};
})();
