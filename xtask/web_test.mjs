// Drives headless Chromium through the page for `cargo xtask web-test` (see
// xtask/src/web_test.rs, which starts the server, renders natively and compares).
//
// usage: node web_test.mjs PLAN.json
// PLAN: { chromium, base_url, out_dir, timeout_ms, cases: [{ name, query }],
//         model: { name, path, level }, bad: { name, path } }
// Writes OUT_DIR/<case>.rgba and .mask (raw bytes) and OUT_DIR/result.json.
import { readFileSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import puppeteer from "puppeteer-core";

const plan = JSON.parse(readFileSync(process.argv[2], "utf8"));
const result = { cases: [], console_errors: [], model: null, bad: null };

// Chromium's own WebGPU (SwiftShader where there is no GPU); no network.
const browserArgs = [
  "--no-sandbox", "--enable-unsafe-webgpu", "--disable-quic", "--no-first-run",
  "--disable-background-networking", "--disable-component-update", "--disable-sync",
];
const browser = await puppeteer.launch({
  executablePath: plan.chromium,
  headless: true,
  args: browserArgs,
  protocolTimeout: plan.timeout_ms,
});

async function openPage(query) {
  const page = await browser.newPage();
  page.on("console", (m) => {
    if (m.type() === "error") result.console_errors.push(`${query}: ${m.text()}`);
  });
  page.on("pageerror", (e) => result.console_errors.push(`${query}: uncaught ${e.message}`));
  const t0 = Date.now();
  await page.goto(plan.base_url + "?" + query, { waitUntil: "load" });
  await page.waitForFunction(
    () => document.title.startsWith("ssbvb ready") || document.title.startsWith("ssbvb error:"),
    { timeout: plan.timeout_ms, polling: 200 },
  );
  return { page, title: await page.title(), wall_ms: Date.now() - t0 };
}

async function bytes(page, fn) {
  const b64 = await page.evaluate(async (fn) => {
    const data = await window.ssbvb[fn]();
    if (data === null) return null;
    let s = "";
    for (let i = 0; i < data.length; i += 0x8000) {
      s += String.fromCharCode.apply(null, data.subarray(i, i + 0x8000));
    }
    return btoa(s);
  }, fn);
  return b64 === null ? null : Buffer.from(b64, "base64");
}

try {
  for (const c of plan.cases) {
    const { page, title, wall_ms } = await openPage(c.query);
    const entry = { name: c.name, title, wall_ms };
    if (title.startsWith("ssbvb ready")) {
      const rgba = await bytes(page, "readPixels");
      writeFileSync(join(plan.out_dir, `${c.name}.rgba`), rgba);
      const mask = await bytes(page, "readVoxelMask");
      if (mask) writeFileSync(join(plan.out_dir, `${c.name}.mask`), mask);
      entry.frames_ms = await page.evaluate(() => window.ssbvb.renderFrames(3));
      entry.stats = await page.evaluate(() => window.ssbvb.stats());
    }
    result.cases.push(entry);
    await page.close();
  }
  if (plan.model) {
    const { page, title } = await openPage(plan.cases[0].query);
    if (title.startsWith("ssbvb ready")) {
      const model = readFileSync(plan.model.path);
      const t0 = Date.now();
      const outcome = await page.evaluate(async (name, b64, level) => {
        const b = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
        try { await window.ssbvb.loadModel(name, b, level); return "ok"; }
        catch (e) { return "rejected: " + e; }
      }, plan.model.name, model.toString("base64"), plan.model.level);
      const ms = Date.now() - t0;
      const mask = await bytes(page, "readVoxelMask");
      const stats = await page.evaluate(() => window.ssbvb.stats());
      result.model = { outcome, ms, title: await page.title(), stats,
        voxel_pixels: mask ? mask.reduce((a, v) => a + v, 0) : null };
      const bad = readFileSync(plan.bad.path);
      const badOutcome = await page.evaluate(async (name, b64) => {
        const b = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
        try { await window.ssbvb.loadModel(name, b, 5); return "ok"; }
        catch (e) { return "rejected: " + e; }
      }, plan.bad.name, bad.toString("base64"));
      result.bad = {
        outcome: badOutcome,
        message: await page.evaluate(() => document.getElementById("message").textContent),
        title: await page.title(),
      };
    } else {
      result.model = { outcome: "page not ready: " + title };
    }
    await page.close();
  }
  // Pages that must fail clearly: a bad URL parameter, and (in a browser without WebGPU
  // enabled) no adapter.
  result.failures = [];
  const bad = await openPage("size=0x0");
  result.failures.push({ case: "bad size", title: bad.title });
  await bad.page.close();
  const plain = await puppeteer.launch({
    executablePath: plan.chromium, headless: true,
    args: browserArgs.filter((a) => a !== "--enable-unsafe-webgpu"),
  });
  try {
    const page = await plain.newPage();
    await page.goto(plan.base_url, { waitUntil: "load" });
    await page.waitForFunction(
      () => document.title.startsWith("ssbvb ready") || document.title.startsWith("ssbvb error:"),
      { timeout: plan.timeout_ms, polling: 200 },
    );
    result.failures.push({ case: "no WebGPU", title: await page.title() });
  } finally {
    await plain.close();
  }
} finally {
  await browser.close();
  writeFileSync(join(plan.out_dir, "result.json"), JSON.stringify(result, null, 1));
}
