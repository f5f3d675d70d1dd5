// mocap view: the playback clock and controls both pages share (the 3-D
// page, viewer.js, and the servo page, servo.js): play/pause, scrub, loop,
// speed, keys, the readout, the URL hash, and the state on <body> for tests.
//
// State for tests, on <body>: data-ready, data-frame, data-playing,
// data-frames. URL hash on load (and on change): #frame=worst | #frame=N,
// &paused=1, &speed=S, &loop=0 (and what opts.hash reads).
"use strict";
// opts: frames, frameTime (s), unit ("frame", "tick"), worst (a frame or
// null), draw(), readout(frame) (text after the times), hash(params).
function mocapPlayer(opts) {
  const N = opts.frames, dt = opts.frameTime, body = document.body;
  const $ = (id) => document.getElementById(id);
  const scrub = $("scrub"), playBtn = $("play"), readout = $("readout");
  const S = { frame: 0, t: 0, playing: true, speed: 1, loop: true };
  scrub.max = String(Math.max(0, N - 1));
  body.dataset.frames = String(N);

  function show() {
    const f = S.frame;
    scrub.value = String(f);
    readout.textContent =
      opts.unit + " " + f + " / " + (N - 1) + " · " + (f * dt).toFixed(3) + " s / " +
      ((N - 1) * dt).toFixed(3) + " s" + opts.readout(f);
    playBtn.textContent = S.playing ? "Pause" : "Play";
    body.dataset.frame = String(f);
    body.dataset.playing = S.playing ? "1" : "0";
    opts.draw();
  }
  function setFrame(f) {
    S.frame = Math.min(N - 1, Math.max(0, Math.round(f)));
    S.t = S.frame * dt;
    show();
  }
  function pauseAt(f) {
    S.playing = false;
    setFrame(f);
  }

  // A timer, not requestAnimationFrame: it follows the page's clock, also a
  // headless browser's virtual time.
  let last = null;
  function tick() {
    const now = performance.now();
    if (S.playing && last != null) {
      S.t += ((now - last) / 1000) * S.speed;
      let f = Math.floor(S.t / dt + 1e-9);
      if (f >= N) {
        if (S.loop && N > 1) {
          S.t %= N * dt;
          f = Math.floor(S.t / dt + 1e-9);
        } else {
          f = N - 1;
          S.playing = false;
        }
      }
      if (f !== S.frame || !S.playing) {
        S.frame = Math.min(N - 1, f);
        show();
      }
    }
    last = now;
    setTimeout(tick, 1000 / 60);
  }

  playBtn.onclick = () => {
    if (!S.playing && S.frame >= N - 1 && !S.loop) setFrame(0);
    S.playing = !S.playing;
    show();
  };
  scrub.oninput = () => setFrame(Number(scrub.value));
  $("loop").onchange = (e) => { S.loop = e.target.checked; };
  $("speed").onchange = (e) => { S.speed = Number(e.target.value); };
  window.addEventListener("keydown", (e) => {
    if (e.target.tagName === "INPUT" && e.target.type === "range") return;
    if (e.key === " ") { e.preventDefault(); playBtn.onclick(); }
    else if (e.key === "ArrowRight") pauseAt(S.frame + 1);
    else if (e.key === "ArrowLeft") pauseAt(S.frame - 1);
  });

  function applyHash() {
    const h = new URLSearchParams(location.hash.replace(/^#/, ""));
    const fr = h.get("frame");
    if (fr === "worst") setFrame(opts.worst == null ? 0 : opts.worst);
    else if (fr != null && fr !== "" && !isNaN(Number(fr))) setFrame(Number(fr));
    if (h.get("paused") === "1") S.playing = false;
    if (h.get("speed")) {
      S.speed = Number(h.get("speed")) || 1;
      $("speed").value = String(S.speed);
    }
    if (h.get("loop") === "0") {
      S.loop = false;
      $("loop").checked = false;
    }
    if (opts.hash) opts.hash(h);
    show();
  }

  return {
    S, show, setFrame, pauseAt,
    start() {
      window.addEventListener("hashchange", applyHash);
      applyHash();
      body.dataset.ready = "1";
      tick();
    },
  };
}
