// mocap view, servo page: a servo clip's pulse curves (report/src/view/servo.rs
// writes the data), one row per servo, against its pulse limits, with a
// playing time cursor; the clock and controls are player.js (frame = tick).
// No libraries, no network.
//
// State for tests, on <body> besides player.js's: data-shaped (ticks at
// which the playback loop changed a command); a show: data-clip (the clip
// playing at the tick shown).
"use strict";
(function () {
  const D = JSON.parse(document.getElementById("motion").textContent);
  const N = D.ticks;
  const n = D.servos.length;
  const body = document.body;
  const dt = 1 / D.rateHz;
  const ROW = 74;
  const LEFT = 150;
  const COLORS = {
    limits: "rgba(214, 120, 110, 0.25)", source: "#c8c8c8", decoded: "#3b6fc4",
    commanded: "#e07b00", shaped: "#b00020", text: "#444", cursor: "#111", neutral: "#c9c4b8",
  };

  const $ = (id) => document.getElementById(id);
  const canvas = $("rows"), g = canvas.getContext("2d");
  const band = $("band"), bg = band.getContext("2d");
  const SH = D.show;
  // Clip colours of the show band (clip index mod length).
  const CLIP_COLORS = ["#8fb3e0", "#a6d49f", "#e6c27a", "#c9a3d9", "#8fd1cc", "#e7a3a3", "#b8b8b8"];
  if (SH) {
    body.classList.add("show");
    $("show-clips").textContent =
      "clips: " + SH.clips.map((c) => c.name + " " + c.seconds.toFixed(2) + " s" + (c.loops ? " (loops)" : "")).join(" · ") +
      " — band: the clip playing, transitions hatched red; ▼ the script's commands and the cues' events";
  }
  $("title").textContent = D.source ? D.source + " + " + D.clip + " (" + D.rig + ")" : D.clip;
  if (!D.sourcePulses) body.classList.add("no-source");
  $("summary").textContent =
    n + " servos · " + N + " ticks at " + D.rateHz.toFixed(2) + " Hz · the playback loop changed the command at " +
    D.shapedTicks + " ticks";
  body.dataset.shaped = String(D.shapedTicks);
  const changedAt = (f) => {
    let k = 0;
    for (let s = 0; s < n; s++) if (D.decoded[s][f] !== D.commanded[s][f]) k++;
    return k;
  };
  // A show: the clip and state at tick f (also data-clip on <body>).
  const playing = (f) => {
    const seg = SH.segments.find((g) => g.from <= f && f < g.to);
    const what = seg && seg.clip != null ? SH.clips[seg.clip].name : "";
    body.dataset.clip = what;
    return seg ? (what || "no clip") + " " + seg.state : "";
  };
  const P = mocapPlayer({
    frames: N, frameTime: dt, unit: "tick", worst: null,
    draw: () => draw(),
    readout: (f) => " · " + changedAt(f) + " servos changed by the loop" + (SH ? " · " + playing(f) : ""),
  });
  const S = P.S;
  let W = 0, dpr = 1;

  function resize() {
    dpr = window.devicePixelRatio || 1;
    const r = canvas.parentElement.getBoundingClientRect();
    W = Math.max(1, Math.round(r.width * dpr));
    canvas.style.height = n * ROW + "px";
    canvas.width = W;
    canvas.height = Math.round(n * ROW * dpr);
    if (SH) {
      band.width = W;
      band.height = Math.round(band.getBoundingClientRect().height * dpr);
    }
    draw();
  }
  // The show band: one box per run of ticks with one clip in one state,
  // transitions hatched, the script's commands and the events as marks.
  function drawBand(w, x) {
    const h = band.height / dpr;
    bg.setTransform(dpr, 0, 0, dpr, 0, 0);
    bg.clearRect(0, 0, w, h);
    bg.font = "11px system-ui, sans-serif";
    bg.fillStyle = COLORS.text;
    bg.fillText("show", 8, 30);
    const top = 16, bh = h - 22;
    for (const seg of SH.segments) {
      const x0 = x(seg.from - 0.5), x1 = x(seg.to - 0.5);
      if (seg.clip == null) continue;
      bg.fillStyle = CLIP_COLORS[seg.clip % CLIP_COLORS.length];
      bg.fillRect(x0, top, x1 - x0, bh);
      if (seg.state === "blending") {
        bg.save();
        bg.beginPath();
        bg.rect(x0, top, x1 - x0, bh);
        bg.clip();
        bg.strokeStyle = "#b00020";
        bg.lineWidth = 1.5;
        for (let k = x0 - bh; k < x1; k += 6) {
          bg.beginPath();
          bg.moveTo(k, top + bh);
          bg.lineTo(k + bh, top);
          bg.stroke();
        }
        bg.restore();
      }
      const label = SH.clips[seg.clip].name + (seg.state === "playing" ? "" : " (" + seg.state + ")");
      if (bg.measureText(label).width + 6 < x1 - x0) {
        bg.fillStyle = "#222";
        bg.fillText(label, x0 + 3, top + bh / 2 + 4);
      }
    }
    bg.fillStyle = COLORS.shaped;
    for (const [t] of SH.cues) {
      const cx = x(t);
      bg.beginPath();
      bg.moveTo(cx - 4, 2);
      bg.lineTo(cx + 4, 2);
      bg.lineTo(cx, 12);
      bg.fill();
    }
    bg.fillStyle = COLORS.cursor;
    bg.fillRect(x(S.frame) - 0.75, 0, 1.5, h);
  }
  function draw() {
    if (!W) return;
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    const w = W / dpr;
    g.clearRect(0, 0, w, n * ROW);
    const x = (t) => LEFT + ((t + 0.5) / Math.max(1, N)) * (w - LEFT - 12);
    if (SH) drawBand(w, x);
    for (let s = 0; s < n; s++) {
      const info = D.servos[s];
      const top = s * ROW + 6, h = ROW - 14;
      // The row's scale: the limits with a margin, widened to every curve.
      let lo = info.minQus, hi = info.maxQus;
      const curves = [D.decoded[s], D.commanded[s]];
      if (D.sourcePulses) curves.push(D.sourcePulses[s]);
      for (const c of curves) for (const v of c) { if (v < lo) lo = v; if (v > hi) hi = v; }
      const pad = Math.max(4, (hi - lo) * 0.12);
      lo -= pad; hi += pad;
      const y = (v) => top + h - ((v - lo) / (hi - lo)) * h;
      // Outside the limits: shaded.
      g.fillStyle = COLORS.limits;
      g.fillRect(LEFT, top, w - LEFT - 12, y(info.maxQus) - top);
      g.fillRect(LEFT, y(info.minQus), w - LEFT - 12, top + h - y(info.minQus));
      g.strokeStyle = COLORS.neutral;
      g.lineWidth = 1;
      g.setLineDash([4, 4]);
      g.beginPath();
      g.moveTo(LEFT, y(info.neutralQus));
      g.lineTo(w - 12, y(info.neutralQus));
      g.stroke();
      g.setLineDash([]);
      const line = (c, colour, width) => {
        g.strokeStyle = colour;
        g.lineWidth = width;
        g.beginPath();
        for (let t = 0; t < N; t++) {
          if (t === 0) g.moveTo(x(t), y(c[t]));
          else g.lineTo(x(t), y(c[t]));
        }
        g.stroke();
      };
      // Widest first: where the loop changed nothing the decoded line lies
      // on the commanded one, and both on the source.
      if (D.sourcePulses) line(D.sourcePulses[s], COLORS.source, 6);
      line(D.commanded[s], COLORS.commanded, 3.5);
      line(D.decoded[s], COLORS.decoded, 1.5);
      g.fillStyle = COLORS.shaped;
      for (const t of D.shaped[s]) g.fillRect(x(t) - 1, top + h - 5, 2, 5);
      // Label: name, limits in µs, the value at the cursor.
      g.fillStyle = COLORS.text;
      g.font = "12px system-ui, sans-serif";
      g.fillText(info.name, 8, top + 14);
      g.fillStyle = "#777";
      g.fillText((info.minQus / 4).toFixed(0) + "–" + (info.maxQus / 4).toFixed(0) + " µs", 8, top + 30);
      const f = Math.min(S.frame, N - 1);
      g.fillText("now " + (D.commanded[s][f] / 4).toFixed(1) + " µs", 8, top + 46);
      g.strokeStyle = "#e4e1da";
      g.beginPath();
      g.moveTo(0, (s + 1) * ROW - 0.5);
      g.lineTo(w, (s + 1) * ROW - 0.5);
      g.stroke();
    }
    g.fillStyle = COLORS.cursor;
    g.fillRect(x(S.frame) - 0.75, 0, 1.5, n * ROW);
  }
  $("next-shaped").onclick = () => {
    for (let k = 1; k <= N; k++) {
      const f = (S.frame + k) % N;
      if (changedAt(f) > 0) return P.pauseAt(f);
    }
  };
  canvas.onclick = (e) => {
    const r = canvas.getBoundingClientRect();
    const px = e.clientX - r.left;
    if (px >= LEFT) P.setFrame(((px - LEFT) / (r.width - LEFT - 12)) * N - 0.5);
  };
  window.onresize = resize;
  resize();
  P.start();
})();
