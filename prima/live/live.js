/* prima live: the run as it happens, drawn as prima show draws a run (PrimaDraw), and
   what the author does as the user, sent to the server. Words are set as text. */
(function () {
  "use strict";
  const $ = function (id) { return document.getElementById(id); };
  const mapDiv = $("map"), timeline = $("timeline"), tbody = document.querySelector("#trace tbody");
  const tableBox = $("table-box"), head = $("playhead"), timelineBox = $("timeline-box");
  const KEEP_ROWS = 1500;      // trace lines kept in the table (the page stays quick)
  const KEEP_WORDS = 200;      // lines of words kept
  const ROBOT_SAYS_FOR = 1.0, USER_SAYS_FOR = 3.0;  // as prima show's bubbles
  const DRAG_PIXELS = 4;       // how far a press must move to drag the user
  const SHARE = 5;             // what grows with the session takes at most 1/SHARE of the time
  let ws = null, D = null, rows = [], poses = [[], []], status = null, statusAt = 0;
  let open = {}, bubbles = [], asking = null, shownBubbles = "", following = true;
  let frames = 0, heard = [], said = [], lastPose = null, pathAt = -1, dragging = false;
  let shownMarkers = "", closed = false, userHigher = false;
  // What waits to be drawn (paced, below): the latest timeline received, the trace lines
  // before which the table has them all, the points walked since the paths were drawn
  // (by trace); and how many timelines were received and drawn.
  let nextTimeline = null, tabled = 0, walked = {}, timelinesIn = 0, timelinesDrawn = 0;
  // The window of the timeline asked for and not received yet (null: none asked), the
  // stretch of the run the timeline drawn covers, and the whole run's (the server's range).
  let asked = null, covers = null, whole = null;
  // The inputs this page sent, the refusals it was sent back, and the last input it sent
  // (its words kept, to put them back in their box if the server refuses them).
  let acts = 0, refusals = 0, firstAdded = 0, lastAct = null, clearAbove = null;
  // What the server answers when it refuses an input of any kind, and what starts its
  // refusals of a say's words and of a message's.
  const REFUSED_ANY = /^(at most \d+ inputs a second|a session takes at most|the run is over)/;
  const REFUSED = {say: /^say: /, message: /^the message/};

  function notice(text, bad) {
    const p = $("notice");
    p.textContent = text;
    p.className = bad ? "bad" : "";
    clearAbove = null;
  }

  /* Say what was refused, until an input sent after it goes through: the server counts
     the inputs it took (status.added), and more of them than this page had sent and not
     been refused so far means a later one was taken. */
  function complain(text) {
    notice(text, true);
    clearAbove = acts - refusals;
  }

  function refused(text) {
    refusals++;
    complain(text);
    const box = lastAct && {say: $("say"), message: $("message")}[lastAct.act];
    if (box && !box.value && (REFUSED_ANY.test(text) || REFUSED[lastAct.act].test(text))) {
      box.value = lastAct.text;  // (what was typed is not lost)
    }
  }

  function banner(text) {
    const b = $("banner");
    b.textContent = text;
    b.hidden = !text;
  }

  function send(message) {
    if (ws && ws.readyState === WebSocket.OPEN) {
      ws.send(JSON.stringify(message));
      if (message.act) { acts++; lastAct = message; }
    } else {
      notice("not connected", true);
    }
  }

  /* Ask for a timeline of the window shown, once the page can draw one (closed: none).
     The server sends one once there is one the page has not had: of a newer trace, or
     of a window the one drawn does not cover. */
  function ask() {
    if (ws && ws.readyState === WebSocket.OPEN) {
      asked = shownWindow();
      ws.send(JSON.stringify({timeline: asked}));
    }
  }

  /* The range shown moved past what the timeline drawn covers: ask again, for the window
     shown now, if a request is out (the page can draw) and it was for a window covered
     (no timeline would come of it before the trace grows). */
  function refill() {
    if (asked && inside(asked, covers) && !inside(shownWindow(), covers)) ask();
  }

  function inside(stretch, span) {
    return span !== null && span[0] <= stretch[0] && stretch[1] <= span[1];
  }

  /* What costs more as the session grows (the trace table, laid out again with each new
     line; the map's paths), or as more of it is shown (the timeline, redrawn whole, or
     its range moved), holds up all else on the page while it is drawn: a click waits
     behind it, and a page that cannot keep up falls ever further behind what comes. So
     each is drawn at most a fifth of the time: after a draw that took d ms, the next
     waits 4 d ms, and draws all that came meanwhile at once (the latest timeline).
     Returns what asks for a draw; once a wait ends with nothing to draw, ready() is
     called. */
  function paced(draw, ready) {
    let wanted = false, timer = null;
    function run() {
      wanted = false;
      const began = performance.now();
      draw();
      timer = setTimeout(function () {
        timer = null;
        if (wanted) run();
        else if (ready) ready();
      }, (SHARE - 1) * (performance.now() - began));
    }
    return function () {
      wanted = true;
      // (by a timer even when due: what came with it, the run's status say, is shown first)
      if (timer === null) timer = setTimeout(run, 0);
    };
  }

  /* What can act: nothing before the session comes, in a tab that does not have it, or
     once the connection is closed; once the run is over, only Save (and the timeline). */
  function setControls() {
    const mine = D !== null && !closed, going = mine && status && status.state === "running";
    document.querySelectorAll("header button, header select, #side button, #side input")
      .forEach(function (c) { c.disabled = !going; });
    $("save").disabled = !mine;
    $("step").disabled = !going || !status.paused;
    $("play").textContent = going && !status.paused ? "Pause" : "Play";
  }

  /* ---------------------------------------------------------------- what comes */

  function connect() {
    ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws");
    ws.onmessage = function (e) { receive(JSON.parse(e.data)); };
    ws.onclose = function () {
      closed = true;
      setControls();
      if (!$("banner").dataset.busy) banner("The connection to prima live is closed: " +
        "the server stopped, or this tab lost it. Reload to take the session again.");
    };
  }

  function receive(m) {
    if (m.hello) hello(m.hello);
    if (m.rows) addRows(m.rows);
    if (m.pose) pose(m.pose);
    if (m.status) setStatus(m.status);
    if (m.timeline) gotTimeline(m);
    if (m.findings) addFindings(m.findings, m.waiting);
    if (m.busy) { $("banner").dataset.busy = "1"; banner(m.busy); }
    if (m.refused) refused(m.refused);
    if (m.saved) notice("saved as " + m.saved + " (save " + m.saves + ")");
    if (m.download) download(m.download);
  }

  function hello(h) {
    D = h;
    const map = h.map;
    map.layout.dragmode = false;
    Plotly.newPlot(mapDiv, map.data, map.layout, map.config);
    Plotly.newPlot(timeline, [], {height: 220, margin: {l: 140, r: 10, t: 30, b: 40},
                                 xaxis: {title: "simulated time (s)"}}, {displaylogo: false});
    // Panned or zoomed, the timeline stays where it was put; double-clicked (Plotly resets
    // its axes just after), it follows the run again.
    let reset = false;
    timeline.on("plotly_doubleclick", function () { reset = true; });
    timeline.on("plotly_relayout", function (e) {
      if (reset) {
        reset = false;
        follow();
      } else if (e && e["xaxis.autorange"]) {  // autoscaled: the whole run, as it was sent
        setFollowing(false);
        if (whole) Plotly.relayout(timeline, {"xaxis.range": whole.slice()});
      } else if (e && e["xaxis.range[0]"] !== undefined) {
        setFollowing(false);
      }
      placeHead();
      refill();
    });
    const senders = $("senders");
    h.senders.forEach(function (s) {
      const o = document.createElement("option");
      o.value = s;
      senders.appendChild(o);
    });
    if (h.senders.length) $("sender").value = h.senders[0];
    $("layout").hidden = !h.layout;
    if (h.foxglove) notice("Foxglove: connect to " + h.foxglove);
    addFindings(h.findings, h.waiting);
    firstAdded = h.status.added;
    setStatus(h.status);
    mapEvents();
    requestAnimationFrame(frame);
    ask();
  }

  function addRows(list) {
    list.forEach(function (row) {
      rows.push(row);
      if (row.kind !== "pose") mark(row);
    });
    tableRows();
  }

  const tableRows = paced(function () {  // the lines not in the table yet (its last KEEP_ROWS)
    const atBottom = tableBox.scrollTop + tableBox.clientHeight >= tableBox.scrollHeight - 30;
    const added = document.createDocumentFragment();
    let i = rows.length, n = 0;
    while (i > tabled && n < KEEP_ROWS) {  // (from the end: none made only to go at once)
      i--;
      if (rows[i].kind !== "pose") n++;
    }
    for (; i < rows.length; i++) {
      if (rows[i].kind !== "pose") added.appendChild(PrimaDraw.tableRow(rows[i], i));
    }
    tabled = rows.length;
    tbody.appendChild(added);
    while (tbody.rows.length > KEEP_ROWS) tbody.deleteRow(0);
    if (atBottom) tableBox.scrollTop = tableBox.scrollHeight;
  });

  function words(who, text, cls) {
    const li = document.createElement("li");
    const b = document.createElement("b");
    b.textContent = who;
    li.appendChild(b);
    li.appendChild(document.createTextNode(" " + text));
    li.className = cls;
    const ol = $("words");
    ol.appendChild(li);
    if (ol.children.length > KEEP_WORDS) ol.removeChild(ol.firstChild);
    ol.scrollTop = ol.scrollHeight;
  }

  function mark(row) {  // what a line changes on the map and in the words
    const t = row.t;
    if (row.kind === "start" && row.text && row.ab != null) {
      open[row.ab] = {t: t, text: row.text};
      words((row.app || "robot") + ":", row.text, "robot");
      if (row.command && row.command.split("+").indexOf("QA") >= 0) {
        asking = row.ab;
        showAsking(row.text);
      }
    } else if (row.kind === "end" && row.ab != null) {
      const o = open[row.ab];
      if (o) {
        bubbles.push(["robot", o.t, Math.max(t, o.t + ROBOT_SAYS_FOR), o.text]);
        delete open[row.ab];
      }
      if (asking === row.ab) { asking = null; showAsking(null); }
    } else if (row.kind === "user") {
      const said = row.action === "say";
      const label = said ? row.text : "[" + PrimaDraw.what(row) + "]";
      bubbles.push(["user", t, t + USER_SAYS_FOR, label]);
      if (said) words("you:", row.text, "user");
    } else if (row.kind === "hear") {
      heard.push({t: t, seq: row.seq, at: performance.now()});
    }
    if (bubbles.length > 50) bubbles = bubbles.slice(-50);
  }

  function showAsking(prompt) {
    $("asking").hidden = !prompt;
    const box = $("answers");
    box.textContent = "";
    if (!prompt) return;
    $("prompt").textContent = prompt;
    D.questions.forEach(function (q) {
      if (prompt.toLowerCase().indexOf(q[0].toLowerCase()) < 0) return;
      q[1].forEach(function (answer) {
        const b = document.createElement("button");
        b.type = "button";
        b.textContent = answer;
        b.addEventListener("click", function () { say(answer); });
        box.appendChild(b);
      });
    });
    setControls();
    $("say").focus();
  }

  function pose(p) {
    const t = p[0];
    [p[1], p[2]].forEach(function (xyh, k) {
      if (!xyh) return;
      const list = poses[k];
      if (list.length && list[list.length - 1][0] >= t) list.pop();
      list.push([t, xyh[0], xyh[1], xyh[2]]);
      if (list.length > 200) list.splice(0, list.length - 200);
    });
    lastPose = p;
    if (t - pathAt >= 0.5 && D) {  // the paths walked, every half second
      pathAt = t;
      [[p[1], D.map.robot - 2], [p[2], D.map.robot - 1]].forEach(function (w) {
        if (!w[0]) return;
        const path = walked[w[1]] || (walked[w[1]] = {x: [], y: []});
        path.x.push(w[0][0]);
        path.y.push(w[0][1]);
      });
      drawPaths();
    }
  }

  const drawPaths = paced(function () {
    const update = {x: [], y: []}, idx = Object.keys(walked).map(Number);
    idx.forEach(function (k) { update.x.push(walked[k].x); update.y.push(walked[k].y); });
    walked = {};
    if (idx.length) Plotly.extendTraces(mapDiv, update, idx);
  });

  function setStatus(s) {
    status = s;
    statusAt = performance.now();
    if (clearAbove !== null && s.added - firstAdded > clearAbove) notice("");
    setControls();
    const speed = $("speed");
    if (speed.value !== String(s.speed)) {
      if (![].some.call(speed.options, function (o) { return o.value === String(s.speed); })) {
        const o = document.createElement("option");
        o.value = String(s.speed);
        o.textContent = s.speed + "x";
        speed.appendChild(o);
      }
      speed.value = String(s.speed);
    }
    const words = {running: s.paused ? "paused" : "", ended: "the run has ended (" +
      s.until.toFixed(2) + " s): save it, or stop the server", stopped: "stopped",
      failed: "the run failed: " + s.error};
    $("state").textContent = words[s.state] || "";
    $("state").className = s.state === "failed" ? "bad" : "";
  }

  function addFindings(list, waiting) {
    const ol = $("findings");
    list.forEach(function (f) {
      const li = document.createElement("li");
      const b = document.createElement("b");
      b.textContent = f.title + " ";
      li.appendChild(b);
      li.appendChild(document.createTextNode(f.line));
      li.dataset.seq = f.seq;
      li.title = "trace line " + f.seq;
      ol.appendChild(li);
    });
    $("waiting").textContent = waiting ? "(" + waiting + " more decided when the run ends)" : "";
  }

  function lastSeconds() {  // the stretch of the timeline that follows the run
    const t = now();
    return [Math.max(0, t - 90), Math.max(t, 30) + 3];
  }

  function shownRange() {  // the timeline's range as drawn, if it is drawn
    return timeline.layout && timeline.layout.xaxis && timeline.layout.xaxis.range;
  }

  function shownWindow() {  // the stretch of the run the timeline shows (following: will)
    const range = shownRange();
    return following || !range ? lastSeconds() : [Number(range[0]), Number(range[1])];
  }

  /* A timeline holds what is seen in the window asked for and a window's width either
     side (its covers), however long the session: redrawn whole, paced, and asked of the
     server only once the page can draw it. Of those that came meanwhile, the latest is
     drawn. */
  function gotTimeline(m) {
    timelinesIn++;
    asked = null;
    nextTimeline = m;
    redrawTimeline();
  }

  const redrawTimeline = paced(function () {
    drawTimeline(nextTimeline);  // (placeHead reads its layout back: timed with it)
    nextTimeline = null;
    timelinesDrawn++;
  }, ask);

  function drawTimeline(m) {
    const fig = m.timeline, layout = fig.layout, shown = shownRange();
    covers = m.covers;
    whole = layout.xaxis.range.slice();
    if (following) layout.xaxis.range = lastSeconds();
    else if (shown) layout.xaxis.range = shown.slice();  // (where it was put)
    layout.uirevision = following ? undefined : "kept";
    Plotly.react(timeline, fig.data, layout, fig.config);
    placeHead();
  }

  function setFollowing(on) {
    following = on;
    $("follow-time").hidden = on;
  }

  function follow() {  // the timeline follows the run's last 90 s again
    setFollowing(true);
    if (timeline.layout) Plotly.relayout(timeline, {"xaxis.range": lastSeconds()});
  }

  /* Following, the range shown moves on once the playhead reaches its end, whether a
     timeline comes or not (a quiet session's trace does not grow, and no timeline comes):
     the range moved, nothing redrawn from new data, paced as a draw is; refill() asks
     for what it moved to. */
  const keepUp = paced(function () {
    if (following) Plotly.relayout(timeline, {"xaxis.range": lastSeconds()});
  });

  function download(d) {
    const url = URL.createObjectURL(new Blob([d.text], {type: "application/xml"}));
    const a = document.createElement("a");
    a.href = url;
    a.download = d.name;
    document.body.appendChild(a);
    a.click();
    a.remove();
    setTimeout(function () { URL.revokeObjectURL(url); }, 10000);
    notice("downloaded as " + d.name);
    window.primaLive.downloaded = d;
  }

  /* ---------------------------------------------------------------- drawing */

  function now() {  // the simulated time shown: the clock, as far as the run has gone
    if (!status) return 0;
    // (the run says how far it has gone, which may be past its latest pose: nothing
    // moved since; while it plays, the clock runs on from its last word, a step behind)
    const latest = Math.max(status.t, lastPose ? lastPose[0] : 0);
    if (status.paused || status.state !== "running") {
      return Math.max(0, Math.min(status.clock, latest, status.until));
    }
    const t = status.clock + (performance.now() - statusAt) / 1000 * status.speed;
    return Math.max(0, Math.min(t, latest + 0.1, status.until) - 0.1);
  }

  function frame() {
    frames++;
    const t = now();
    const robot = PrimaDraw.poseAt(poses[0], t), user = PrimaDraw.poseAt(poses[1], t);
    const markers = JSON.stringify([robot, user].map(function (p) {
      return p ? [p[1].toFixed(3), p[2].toFixed(3), p[3].toFixed(1)] : null;
    }));
    if (!dragging && markers !== shownMarkers) {  // (redrawn only when they moved)
      shownMarkers = markers;
      PrimaDraw.markers(mapDiv, robot, user, D.map.robot, D.map.user);
    }
    // The bubbles of whoever is higher on the map go up, the other's down: the robot's
    // and the user's never cover each other, however close they stand.
    const out = [], seen = {robot: 0, user: 0};
    if (robot && user && Math.abs(user[2] - robot[2]) > 0.1) userHigher = user[2] > robot[2];
    const below = {robot: userHigher, user: !userHigher};
    Object.keys(open).forEach(function (ab) {
      if (robot) {
        out.push(PrimaDraw.bubble("robot", robot, open[ab].text, seen.robot++, below.robot));
      }
    });
    bubbles.forEach(function (b) {
      if (b[1] > t + 0.2 || t > b[2]) return;
      const at = b[0] === "robot" ? robot : user;
      if (at && seen[b[0]] < 3) {
        out.push(PrimaDraw.bubble(b[0], at, b[3], seen[b[0]]++, below[b[0]]));
      }
    });
    const key = JSON.stringify(out);
    if (key !== shownBubbles) {
      shownBubbles = key;
      Plotly.relayout(mapDiv, {annotations: out});
    }
    const clock = t.toFixed(2) + " s";
    // (written only when it changed: any change has the whole page laid out and painted
    // again, which a long session's timeline makes costly)
    if ($("clock").textContent !== clock) $("clock").textContent = clock;
    const range = shownRange();
    if (following && range && t > range[1]) keepUp();
    placeHead(t);
    requestAnimationFrame(frame);
  }

  function placeHead(t) {  // a line over the timeline (moving it redraws nothing)
    const area = timeline.querySelector(".nsewdrag");
    const range = shownRange();
    if (!area || !range) { head.style.display = "none"; return; }
    const at = t === undefined ? now() : t;
    const r = area.getBoundingClientRect(), box = timelineBox.getBoundingClientRect();
    const x = r.left - box.left + (at - range[0]) / (range[1] - range[0]) * r.width;
    head.style.display = x >= r.left - box.left && x <= r.right - box.left ? "block" : "none";
    head.style.left = x + "px";
    head.style.top = (r.top - box.top) + "px";
    head.style.height = r.height + "px";
  }

  /* ---------------------------------------------------------------- what the author does */

  function say(text) {
    if (!text.trim()) {
      $("say").value = "";
      complain("say: type some words first");
      return;
    }
    said.push(performance.now());
    send({act: "say", text: text});
    $("say").value = "";
  }

  function toMap(e) {  // a mouse event's point, in metres on the map
    const l = mapDiv._fullLayout;
    if (!l || !l.xaxis || !l.yaxis) return null;
    const r = mapDiv.querySelector(".nsewdrag").getBoundingClientRect();
    return [l.xaxis.p2c(e.clientX - r.left), l.yaxis.p2c(e.clientY - r.top)];
  }

  function near(point, pose, metres) {
    return point && pose && Math.hypot(point[0] - pose[1], point[1] - pose[2]) <= metres;
  }

  /* A press near the user that moves more than a few pixels drags the user (a walk);
     a click without a drag never walks: near the robot, it touches the robot, even with
     the user beside it. */
  function mapEvents() {
    let from = null, grabbed = false;
    mapDiv.addEventListener("mousedown", function (e) {
      if (closed || (status && status.state !== "running")) return;
      from = [e.clientX, e.clientY];
      grabbed = near(toMap(e), PrimaDraw.poseAt(poses[1], now()), 0.6);
      if (grabbed) e.preventDefault();
    });
    mapDiv.addEventListener("mousemove", function (e) {
      if (!grabbed) return;
      if (!dragging && Math.hypot(e.clientX - from[0], e.clientY - from[1]) <= DRAG_PIXELS) return;
      dragging = true;
      const to = toMap(e);
      if (to) Plotly.restyle(mapDiv, {x: [[to[0]]], y: [[to[1]]]}, [D.map.user]);
    });
    window.addEventListener("mouseup", function (e) {
      if (from === null) return;
      const to = toMap(e);
      if (dragging && to) {
        send({act: "walk", x: Math.round(to[0] * 100) / 100, y: Math.round(to[1] * 100) / 100});
      } else if (!dragging && near(to, PrimaDraw.poseAt(poses[0], now()), 0.6)) {
        send({act: "touch"});
      }
      dragging = grabbed = false;
      shownMarkers = "";  // (the user's marker goes back to where the user is)
      from = null;
    });
  }

  $("say-form").addEventListener("submit", function (e) {
    e.preventDefault();
    say($("say").value);
  });
  $("message-form").addEventListener("submit", function (e) {
    e.preventDefault();
    send({act: "message", sender: $("sender").value, text: $("message").value});
    $("message").value = "";
  });
  ["touch", "follow", "stop"].forEach(function (act) {
    $(act).addEventListener("click", function () { send({act: act}); });
  });
  $("play").addEventListener("click", function () {
    send({control: status && status.paused ? "play" : "pause"});
  });
  $("step").addEventListener("click", function () {
    send({control: "step", seconds: Number($("step-by").value)});
  });
  $("speed").addEventListener("change", function () {
    send({control: "speed", speed: Number($("speed").value)});
  });
  $("save").addEventListener("click", function () { send({save: true}); });
  $("follow-time").addEventListener("click", follow);

  /* The space bar plays and pauses wherever the focus is (a button just clicked, a list
     just chosen from), except in a box one types in. Kept from the focused button, it
     does not click it again (a button clicks as the space bar comes up). */
  const NOT_TYPED = /^(button|checkbox|color|file|image|radio|range|reset|submit)$/;
  function typing(target) {
    return target.isContentEditable || target.tagName === "TEXTAREA" ||
      (target.tagName === "INPUT" && !NOT_TYPED.test(target.type));
  }
  document.addEventListener("keydown", function (e) {
    if (e.key !== " " || e.ctrlKey || e.altKey || e.metaKey || typing(e.target)) return;
    e.preventDefault();
    if (!e.repeat) $("play").click();
  });
  document.addEventListener("keyup", function (e) {
    if (e.key === " " && !typing(e.target)) e.preventDefault();
  });

  // Speech, where the browser recognises it; typed words always work.
  const Recognition = window.SpeechRecognition || window.webkitSpeechRecognition;
  if (Recognition) {
    const mic = $("mic");
    mic.hidden = false;
    let listening = null;
    mic.addEventListener("click", function () {
      if (listening) { listening.stop(); return; }
      listening = new Recognition();
      listening.lang = "en-US";
      listening.onresult = function (e) {
        const r = e.results[e.results.length - 1];
        if (r.isFinal) say(r[0].transcript);
      };
      listening.onend = function () { listening = null; mic.classList.remove("on"); };
      listening.onerror = function (e) { notice("speech: " + e.error, true); };
      mic.classList.add("on");
      listening.start();
    });
  }

  // For tests and benchmarks: what the page has, read through the browser.
  window.primaLive = {
    rows: function () { return rows; },
    frames: function () { return frames; },
    heard: function () { return heard; },
    said: function () { return said; },
    pose: function () { return lastPose; },
    time: now,
    status: function () { return status; },
    timelines: function () {
      return {received: timelinesIn, drawn: timelinesDrawn, covers: covers, asked: asked};
    },
    ready: function () { return D !== null; },
    downloaded: null,
  };
  connect();
})();
