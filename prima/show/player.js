/* prima show: one playhead drives the map, the timeline and the trace table.
   Data: PRIMA_SHOW (written by prima.show); drawing: Plotly (inlined above). */
(function () {
  "use strict";
  const D = PRIMA_SHOW;
  const mapDiv = document.getElementById("map");
  const timeline = document.getElementById("timeline");
  const tbody = document.querySelector("#trace tbody");
  const details = document.getElementById("details");
  const playButton = document.getElementById("play");
  const speed = document.getElementById("speed");
  const scrub = document.getElementById("scrub");
  const clock = document.getElementById("clock");
  const timelineBox = document.getElementById("timeline-box");
  const head = document.getElementById("playhead");
  const times = D.rows.map(function (r) { return r.t; });
  const soundOn = document.getElementById("sound");
  const sounds = Array.prototype.map.call(document.querySelectorAll("#sounds audio"),
    function (el) { return {el: el, start: Number(el.dataset.start), end: Number(el.dataset.end)}; });
  let now = 0, playing = false, last = null, shownRow = -1, shownBubbles = "";

  const esc = PrimaDraw.esc, what = PrimaDraw.what, poseAt = PrimaDraw.poseAt;

  /* The trace table. */
  const trs = D.rows.map(function (row, i) {
    const tr = PrimaDraw.tableRow(row, i);
    tr.className = "future";
    tbody.appendChild(tr);
    return tr;
  });
  tbody.addEventListener("click", function (e) {
    const tr = e.target.closest("tr");
    if (tr) choose(Number(tr.dataset.i));
  });

  function lastRowAt(t) {  // the last line at or before t, or -1
    let lo = 0, hi = times.length;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (times[mid] <= t + 1e-9) lo = mid + 1; else hi = mid;
    }
    return lo - 1;
  }

  function bubblesAt(t, robot, user) {
    const out = [];
    const seen = {robot: 0, user: 0};
    D.bubbles.forEach(function (b) {
      if (b[1] > t || t > b[2]) return;
      const pose = b[0] === "robot" ? robot : user;
      if (pose) out.push(PrimaDraw.bubble(b[0], pose, b[3], seen[b[0]]++));
    });
    return out;
  }

  function render() {
    scrub.value = now;
    clock.textContent = now.toFixed(2) + " s";
    const robot = poseAt(D.robot, now), user = poseAt(D.user, now);
    PrimaDraw.markers(mapDiv, robot, user, D.robotTrace, D.userTrace);
    const bubbles = bubblesAt(now, robot, user);
    const key = JSON.stringify(bubbles);
    if (key !== shownBubbles) {
      shownBubbles = key;
      Plotly.relayout(mapDiv, {annotations: bubbles});
    }
    placeHead();
    voice();
    const row = lastRowAt(now);
    if (row !== shownRow) {
      const lo = Math.min(row, shownRow), hi = Math.max(row, shownRow);
      for (let i = Math.max(lo, 0); i <= hi; i++) {
        trs[i].className = (i <= row ? "past" : "future") +
          (trs[i].classList.contains("chosen") ? " chosen" : "");
      }
      if (row >= 0) {
        trs[row].classList.add("now");
        const box = document.getElementById("table-box");
        const top = trs[row].offsetTop - box.clientHeight / 2;
        box.scrollTop = Math.max(0, top);
      }
      shownRow = row;
    }
  }

  /* The words, heard: each utterance's sound plays while the playhead is inside it, from
     where the playhead is, at the playback speed (up to 4x; faster, it is silent). */
  function voice() {
    const rate = Number(speed.value);
    const on = playing && rate <= 4 && (!soundOn || soundOn.checked);
    sounds.forEach(function (s) {
      const el = s.el, at = now - s.start;
      if (on && s.start <= now && now < s.end) {
        if (el.playbackRate !== rate) el.playbackRate = rate;
        if (el.paused) {
          el.currentTime = at;
          const started = el.play();
          if (started) started.catch(function () {});
        } else if (Math.abs(el.currentTime - at) > 0.3) {
          el.currentTime = at;
        }
      } else if (!el.paused) {
        el.pause();
      }
    });
  }

  /* The playhead: a line over the timeline's plot area (moving it redraws nothing). */
  function placeHead() {
    const area = timeline.querySelector(".nsewdrag");
    const range = timeline.layout.xaxis.range;
    if (!area || !range) return;
    const r = area.getBoundingClientRect(), box = timelineBox.getBoundingClientRect();
    const x = r.left - box.left + (now - range[0]) / (range[1] - range[0]) * r.width;
    const inside = x >= r.left - box.left && x <= r.right - box.left;
    head.style.display = inside ? "block" : "none";
    head.style.left = x + "px";
    head.style.top = (r.top - box.top) + "px";
    head.style.height = r.height + "px";
  }
  timeline.on("plotly_relayout", placeHead);
  window.addEventListener("resize", placeHead);

  function seek(t) {
    now = Math.max(0, Math.min(D.end, t));
    render();
  }

  /* The clock that plays the run: the browser's animation frames, each called with its
     time stamp in milliseconds. primaShow.useClock(schedule) hands the frames to another
     (a test's, which steps them at the stamps it chooses). */
  let nextFrame = function (callback) { window.requestAnimationFrame(callback); };

  function frame(stamp) {
    if (!playing) return;
    if (last !== null) now += (stamp - last) / 1000 * Number(speed.value);
    last = stamp;
    if (now >= D.end) { now = D.end; pause(); }
    render();
    if (playing) nextFrame(frame);
  }

  function play() {
    if (now >= D.end) now = 0;
    playing = true; last = null; playButton.textContent = "Pause";
    nextFrame(frame);
  }

  function pause() { playing = false; playButton.textContent = "Play"; voice(); }

  playButton.addEventListener("click", function () { if (playing) pause(); else play(); });
  scrub.addEventListener("input", function () { seek(Number(scrub.value)); });
  document.addEventListener("keydown", function (e) {  // space: play/pause; arrows: a second
    if (/^(INPUT|SELECT|BUTTON|TEXTAREA)$/.test(e.target.tagName)) return;
    if (e.key === " ") { if (playing) pause(); else play(); }
    else if (e.key === "ArrowRight") seek(now + 1);
    else if (e.key === "ArrowLeft") seek(now - 1);
    else return;
    e.preventDefault();
  });

  /* Details: why the mediator decided a line, or what an AB did. */
  function rowDetails(row) {
    let out = "<h2>" + esc(row.kind) + (row.app ? " by " + esc(row.app) : "") + " at " +
      row.t.toFixed(2) + " s</h2>";
    if (row.reason) out += '<p>reason: <span class="reason">' + esc(row.reason) + "</span></p>";
    return out + "<p>" + esc(what(row)) + "</p><pre>" + esc(JSON.stringify(row, null, 1)) +
      "</pre>";
  }

  function abDetails(ab) {
    const info = D.abs[ab];
    const start = D.rows[info.start], end = info.end == null ? null : D.rows[info.end];
    let out = "<h2>AB " + ab + ": " + esc(start.command || "") + " (" + esc(start.app || "") +
      ")</h2><p>" + esc(what(start)) + "</p><p>on " + esc((start.devices || []).join(", ")) +
      "</p>";
    info.lines.forEach(function (i) {
      const row = D.rows[i];
      out += "<p>" + row.t.toFixed(2) + " s " + esc(row.kind) +
        (row.reason ? ': <span class="reason">' + esc(row.reason) + "</span>" : "") +
        (row.kind !== "start" && row.text ? " (" + esc(row.text) + ")" : "") + "</p>";
    });
    if (!end) out += "<p>still running when the trace ends</p>";
    return out;
  }

  function mark(i) {
    trs.forEach(function (tr) { tr.classList.remove("chosen"); });
    if (i >= 0) trs[i].classList.add("chosen");
  }

  function choose(i) {
    pause();
    mark(i);
    const row = D.rows[i];
    details.innerHTML = row.ab != null && D.abs[row.ab] && D.abs[row.ab].start != null ?
      rowDetails(row) + abDetails(row.ab) : rowDetails(row);
    seek(row.t);
  }

  function chooseAb(ab) {
    pause();
    const info = D.abs[ab];
    mark(info.start);
    details.innerHTML = abDetails(ab);
    seek(D.rows[info.start].t);
  }

  timeline.on("plotly_click", function (event) {
    const point = event.points[0];
    if (!point) return;
    const kind = point.data.meta;
    if (kind === "bars") chooseAb(String(point.customdata));
    else choose(point.customdata);
  });

  window.primaShow = {
    abs: Object.keys(D.abs).filter(function (k) { return D.abs[k].start != null; }),
    seek: seek, play: play, pause: pause, chooseAb: chooseAb,
    time: function () { return now; },
    useClock: function (schedule) { nextFrame = schedule; },
    sounds: function () {
      return sounds.map(function (s) {
        return {start: s.start, end: s.end, duration: s.el.duration, ready: s.el.readyState,
                error: s.el.error ? s.el.error.code : 0, paused: s.el.paused,
                at: s.el.currentTime, expected: Number(s.el.dataset.duration)};
      });
    },
  };
  render();
})();
