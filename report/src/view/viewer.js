// mocap view: plays the motion embedded in the page (report/src/view/mod.rs
// writes it; pack.rs says how it is packed) as a 3-D skeleton on a 2-D
// canvas with a small perspective camera; the clock and controls are
// player.js. No libraries, no network.
//
// State for tests, on <body> besides player.js's: data-worst, data-view (the
// 3-D view's x,y,w,h in CSS px), data-probe (see probe()). URL hash besides player.js's: &side=1.
"use strict";
(function () {
  const D = JSON.parse(document.getElementById("motion").textContent);
  const N = D.frames;
  const J = D.joints.length;
  const body = document.body;
  const hasClip = D.residuals != null;
  const COLOR_ORIGINAL = "#3b6fc4";
  const COLOR_GRID = "#dcd8cf";
  const COLOR_GRID_AXIS = "#c4bfb3";

  // ---- unpacking (pack.rs) ----
  function bytes(b64) {
    const s = atob(b64);
    const u = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) u[i] = s.charCodeAt(i);
    return new DataView(u.buffer);
  }
  // Marker clips: samples the source lacks (mod.rs `missing`): drawn hollow,
  // without bones, never as data.
  const miss = D.missing ? bytes(D.missing) : null;
  function missing(f, j) {
    if (!miss) return false;
    const i = f * J + j;
    return (miss.getUint8(i >> 3) >> (i & 7)) & 1;
  }
  const q = D.quantumMm;
  const orig = new Float32Array(N * J * 3);
  const dec = hasClip ? new Float32Array(N * J * 3) : null;
  {
    const acc = D.first.slice();
    const deltas = bytes(D.deltas);
    const resid = hasClip ? bytes(D.residuals) : null;
    const stride = J * 3;
    for (let f = 0; f < N; f++) {
      for (let k = 0; k < stride; k++) {
        if (f > 0) acc[k] += deltas.getInt16(((f - 1) * stride + k) * 2, true);
        const i = f * stride + k;
        orig[i] = acc[k] * q;
        if (resid) dec[i] = (acc[k] + resid.getInt16(i * 2, true)) * q;
      }
    }
  }
  const err = hasClip ? new Float32Array(N * J) : null;
  const frameMax = new Float32Array(N);
  const frameRms = new Float32Array(N);
  let errScale = 1;
  if (hasClip) {
    const e = bytes(D.errors);
    let all = 0;
    for (let f = 0; f < N; f++) {
      let sq = 0, mx = 0;
      for (let j = 0; j < J; j++) {
        const v = e.getUint16((f * J + j) * 2, true) * D.errorQuantumMm;
        err[f * J + j] = v;
        sq += v * v;
        if (v > mx) mx = v;
      }
      frameMax[f] = mx;
      frameRms[f] = Math.sqrt(sq / J);
      if (mx > all) all = mx;
    }
    errScale = Math.max(all, D.errorQuantumMm);
  }
  const worst = hasClip ? D.worstFrame : 0;

  // ---- scene extents ----
  // `size`: the body's largest extent in any frame (not frame 0's: CMU's
  // first frame is a reference pose); each frame's centre (mean of its
  // joints' x and z, the middle of its heights), which the camera follows
  // (the root of some rigs stays put while the hips move, and a climb lifts
  // the whole body), and the middle of all of them.
  let floor = Infinity, size = 1;
  const centre = new Float32Array(N * 3);
  let cx0 = Infinity, cx1 = -Infinity, cz0 = Infinity, cz1 = -Infinity;
  let cy0 = Infinity, cy1 = -Infinity;
  for (let f = 0; f < N; f++) {
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    let sx = 0, sz = 0;
    for (let j = 0; j < J; j++) {
      const at = (f * J + j) * 3;
      // Extents without the root when it has joints below (a rig's root
      // such as iclone's RL_BoneRoot stays at the origin as the body walks).
      for (let k = 0; k < 3 && (j > 0 || J === 1); k++) {
        const v = orig[at + k];
        if (v < lo[k]) lo[k] = v;
        if (v > hi[k]) hi[k] = v;
      }
      sx += orig[at];
      sz += orig[at + 2];
    }
    size = Math.max(size, hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    floor = Math.min(floor, lo[1]);
    const x = sx / J, y = (lo[1] + hi[1]) / 2, z = sz / J;
    centre[f * 3] = x;
    centre[f * 3 + 1] = y;
    centre[f * 3 + 2] = z;
    cx0 = Math.min(cx0, x); cx1 = Math.max(cx1, x);
    cy0 = Math.min(cy0, y); cy1 = Math.max(cy1, y);
    cz0 = Math.min(cz0, z); cz1 = Math.max(cz1, z);
  }
  const gridStep = niceStep(size / 3);
  function niceStep(x) {
    const p = Math.pow(10, Math.floor(Math.log10(x)));
    const m = x / p;
    return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
  }

  // ---- view state (the clock is player.js's) ----
  const V = {
    side: false, follow: true, showOriginal: true, showDecoded: true,
    yaw: 0.6, pitch: 0.25, dist: size * 2.6,
  };

  // ---- elements ----
  const $ = (id) => document.getElementById(id);
  const view = $("view"), strip = $("strip");
  const g = view.getContext("2d");
  const sg = strip.getContext("2d");
  $("title").textContent = D.clip ? D.source + " + " + D.clip : D.source;
  if (!hasClip) body.classList.add("no-clip");
  if (D.metrics) {
    const m = D.metrics;
    $("summary").textContent =
      m.bytes + " B · ARMS " + m.arms_mm.toFixed(2) + " mm · max " + m.max_joint_err_mm.toFixed(2) +
      " mm (" + m.max_joint_err_joint + ", frame " + m.max_joint_err_frame + ") · angle max " +
      m.angle_max_deg.toFixed(3) + "°" +
      (D.missingCount ? " · " + D.missingCount + " samples missing in the source (hollow; errors there are against the encoder's fill)" : "");
    $("legend").innerHTML =
      '<div>joint error</div><div class="bar"></div><div class="ends"><span>0 mm</span><span>' +
      errScale.toFixed(1) + " mm</span></div>";
    $("strip-label").textContent =
      "per-frame joint error: bars max, line RMS (0–" + errScale.toFixed(1) +
      " mm); ▲ worst frame " + worst + "; click to jump";
  }
  if (hasClip) body.dataset.worst = String(worst);
  // data-probe: the last joint's unpacked position (mm) at frame f, the
  // decoded one's, and the frame's largest joint error, so a test can check
  // the unpacking against the encoder's own numbers.
  function probe(f) {
    const i = (f * J + J - 1) * 3;
    const p = [orig[i], orig[i + 1], orig[i + 2]];
    if (hasClip) p.push(dec[i], dec[i + 1], dec[i + 2], frameMax[f]);
    body.dataset.probe = p.map((v) => v.toFixed(3)).join(",");
  }
  const P = mocapPlayer({
    frames: N, frameTime: D.frameTime, unit: "frame", worst: hasClip ? worst : null,
    draw: () => draw(),
    readout: (f) => {
      probe(f);
      return hasClip ? " · max " + frameMax[f].toFixed(2) + " mm" : "";
    },
    hash: (h) => {
      if (h.get("side") === "1") { V.side = true; $("side").checked = true; }
    },
  });
  const S = P.S;

  // ---- camera ----
  let W = 0, H = 0, dpr = 1;
  function resize() {
    dpr = window.devicePixelRatio || 1;
    const r = view.getBoundingClientRect();
    W = Math.max(1, Math.round(r.width * dpr));
    H = Math.max(1, Math.round(r.height * dpr));
    view.width = W;
    view.height = H;
    body.dataset.view = [r.left, r.top, r.width, r.height].map(Math.round).join(",");
    const sr = strip.getBoundingClientRect();
    strip.width = Math.max(1, Math.round(sr.width * dpr));
    strip.height = Math.max(1, Math.round(sr.height * dpr));
    draw();
  }
  function target() {
    const f = S.frame;
    if (V.follow) return [centre[f * 3], centre[f * 3 + 1], centre[f * 3 + 2]];
    return [(cx0 + cx1) / 2, (cy0 + cy1) / 2, (cz0 + cz1) / 2];
  }
  function camera() {
    const t = target();
    const cp = Math.cos(V.pitch), sp = Math.sin(V.pitch);
    const dir = [cp * Math.sin(V.yaw), sp, cp * Math.cos(V.yaw)];
    const eye = [t[0] + V.dist * dir[0], t[1] + V.dist * dir[1], t[2] + V.dist * dir[2]];
    const fwd = [-dir[0], -dir[1], -dir[2]];
    // right = fwd × (0, 1, 0); up = right × fwd
    let right = [-fwd[2], 0, fwd[0]];
    const rl = Math.hypot(right[0], right[2]) || 1;
    right = [right[0] / rl, 0, right[2] / rl];
    const up = [
      right[1] * fwd[2] - right[2] * fwd[1],
      right[2] * fwd[0] - right[0] * fwd[2],
      right[0] * fwd[1] - right[1] * fwd[0],
    ];
    const focal = (Math.min(W, H * 1.4) / 2) / Math.tan(0.5 * 0.75);
    return { eye, fwd, right, up, focal };
  }
  const NEAR = 1;
  function toCam(c, p) {
    const d0 = p[0] - c.eye[0], d1 = p[1] - c.eye[1], d2 = p[2] - c.eye[2];
    return [
      d0 * c.right[0] + d1 * c.right[1] + d2 * c.right[2],
      d0 * c.up[0] + d1 * c.up[1] + d2 * c.up[2],
      d0 * c.fwd[0] + d1 * c.fwd[1] + d2 * c.fwd[2],
    ];
  }
  function proj(c, v) {
    return [W / 2 + (c.focal * v[0]) / v[2], H / 2 - (c.focal * v[1]) / v[2]];
  }
  // A world segment, clipped to the near plane; false when all behind.
  function segment(c, a, b) {
    let u = toCam(c, a), v = toCam(c, b);
    if (u[2] < NEAR && v[2] < NEAR) return false;
    if (u[2] < NEAR || v[2] < NEAR) {
      const s = (NEAR - u[2]) / (v[2] - u[2]);
      const m = [u[0] + s * (v[0] - u[0]), u[1] + s * (v[1] - u[1]), NEAR];
      if (u[2] < NEAR) u = m; else v = m;
    }
    const p = proj(c, u), r = proj(c, v);
    g.moveTo(p[0], p[1]);
    g.lineTo(r[0], r[1]);
    return true;
  }

  // ---- drawing ----
  function heat(x) {
    // 0 → green, 0.5 → yellow, 1 → red (the legend's gradient)
    const stops = [[26, 152, 80], [254, 224, 139], [215, 48, 39]];
    const t = Math.min(1, Math.max(0, x)) * 2;
    const i = Math.min(1, Math.floor(t));
    const a = stops[i], b = stops[i + 1], s = t - i;
    return "rgb(" + [0, 1, 2].map((k) => Math.round(a[k] + s * (b[k] - a[k]))).join(",") + ")";
  }
  function grid(c) {
    const t = target();
    const n = 8;
    const cx = Math.round(t[0] / gridStep) * gridStep, cz = Math.round(t[2] / gridStep) * gridStep;
    g.lineWidth = Math.max(1, dpr);
    for (let i = -n; i <= n; i++) {
      const x = cx + i * gridStep, z = cz + i * gridStep;
      g.strokeStyle = Math.abs(x) < gridStep / 2 ? COLOR_GRID_AXIS : COLOR_GRID;
      g.beginPath();
      segment(c, [x, floor, cz - n * gridStep], [x, floor, cz + n * gridStep]);
      g.stroke();
      g.strokeStyle = Math.abs(z) < gridStep / 2 ? COLOR_GRID_AXIS : COLOR_GRID;
      g.beginPath();
      segment(c, [cx - n * gridStep, floor, z], [cx + n * gridStep, floor, z]);
      g.stroke();
    }
  }
  function at(arr, f, j, shift) {
    const i = (f * J + j) * 3;
    return [arr[i] + shift[0], arr[i + 1], arr[i + 2] + shift[2]];
  }
  function skeleton(c, arr, f, shift, colour, width) {
    g.lineCap = "round";
    g.lineWidth = width * dpr;
    for (let j = 0; j < J; j++) {
      const p = D.joints[j].parent;
      if (p == null || missing(f, p) || missing(f, j)) continue;
      g.strokeStyle = colour(j);
      g.beginPath();
      if (segment(c, at(arr, f, p, shift), at(arr, f, j, shift))) g.stroke();
    }
    for (let j = 0; j < J; j++) {
      const v = toCam(c, at(arr, f, j, shift));
      if (v[2] < NEAR) continue;
      const s = proj(c, v);
      g.beginPath();
      g.arc(s[0], s[1], (width * 0.9 + 1) * dpr, 0, 2 * Math.PI);
      if (missing(f, j)) {
        g.lineWidth = Math.max(1, dpr);
        g.strokeStyle = "#9a958a";
        g.stroke();
        g.lineWidth = width * dpr;
      } else {
        g.fillStyle = colour(j);
        g.fill();
      }
    }
  }
  function draw() {
    if (!W) return;
    g.clearRect(0, 0, W, H);
    const c = camera();
    grid(c);
    const f = S.frame;
    const off = V.side && hasClip ? size * 0.45 : 0;
    const sl = [-c.right[0] * off, 0, -c.right[2] * off];
    const sr = [c.right[0] * off, 0, c.right[2] * off];
    const width = hasClip && !V.side ? 5 : 3.5; // under the decoded one: wider
    if (V.showOriginal || !hasClip) skeleton(c, orig, f, sl, () => COLOR_ORIGINAL, width);
    if (hasClip && V.showDecoded) {
      skeleton(c, dec, f, sr, (j) => heat(err[f * J + j] / errScale), 2.5);
    }
    drawStrip();
  }
  function drawStrip() {
    if (!hasClip) return;
    const w = strip.width, h = strip.height;
    sg.clearRect(0, 0, w, h);
    sg.fillStyle = "#f0eee8";
    sg.fillRect(0, 0, w, h);
    const x = (f) => ((f + 0.5) / N) * w;
    const y = (v) => h - 2 - (v / errScale) * (h - 10);
    const bw = Math.max(1, w / N);
    for (let f = 0; f < N; f++) {
      sg.fillStyle = heat(frameMax[f] / errScale);
      sg.fillRect(x(f) - bw / 2, y(frameMax[f]), bw, h - 2 - y(frameMax[f]));
    }
    sg.strokeStyle = "#333";
    sg.lineWidth = dpr;
    sg.beginPath();
    for (let f = 0; f < N; f++) {
      if (f === 0) sg.moveTo(x(f), y(frameRms[f]));
      else sg.lineTo(x(f), y(frameRms[f]));
    }
    sg.stroke();
    sg.fillStyle = "#b00020";
    sg.beginPath();
    sg.moveTo(x(worst), 0);
    sg.lineTo(x(worst) - 5 * dpr, 8 * dpr);
    sg.lineTo(x(worst) + 5 * dpr, 8 * dpr);
    sg.fill();
    sg.fillStyle = "#111";
    sg.fillRect(x(S.frame) - dpr, 0, 2 * dpr, h);
  }
  // ---- input ----
  $("follow").onchange = (e) => { V.follow = e.target.checked; draw(); };
  $("showOriginal").onchange = (e) => { V.showOriginal = e.target.checked; draw(); };
  $("showDecoded").onchange = (e) => { V.showDecoded = e.target.checked; draw(); };
  $("side").onchange = (e) => { V.side = e.target.checked; draw(); };
  $("worst").onclick = () => P.pauseAt(worst);
  strip.onclick = (e) => {
    const r = strip.getBoundingClientRect();
    P.setFrame(Math.floor(((e.clientX - r.left) / r.width) * N));
  };
  let drag = null;
  view.onpointerdown = (e) => {
    drag = [e.clientX, e.clientY];
    view.classList.add("dragging");
    view.setPointerCapture(e.pointerId);
  };
  view.onpointermove = (e) => {
    if (!drag) return;
    V.yaw -= (e.clientX - drag[0]) * 0.01;
    V.pitch = Math.min(1.45, Math.max(-0.2, V.pitch + (e.clientY - drag[1]) * 0.01));
    drag = [e.clientX, e.clientY];
    draw();
  };
  view.onpointerup = () => { drag = null; view.classList.remove("dragging"); };
  view.onwheel = (e) => {
    e.preventDefault();
    V.dist = Math.min(size * 40, Math.max(size * 0.3, V.dist * Math.exp(e.deltaY * 0.001)));
    draw();
  };
  window.onresize = resize;
  resize();
  P.start();
})();
