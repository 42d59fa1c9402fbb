import puppeteer from "puppeteer-core";
const base = process.argv[2];
const args = ["--no-sandbox", "--enable-unsafe-webgpu", "--disable-quic", "--no-first-run",
  "--disable-background-networking", "--disable-component-update", "--disable-sync"];
const browser = await puppeteer.launch({ executablePath: "/usr/bin/chromium", headless: true, args, protocolTimeout: 600000 });
for (const q of process.argv.slice(3)) {
  const page = await browser.newPage();
  await page.goto(base + "?" + q);
  await page.waitForFunction(() => document.title.startsWith("ssbvb ready") || document.title.startsWith("ssbvb error"), { timeout: 300000, polling: 200 });
  const title = await page.title();
  let frames = [];
  for (let i = 0; i < 5; i++) { await page.evaluate(() => window.ssbvb.renderFrames(1)); frames.push((await page.evaluate(() => window.ssbvb.stats())).frame_ms); }
  const s = await page.evaluate(() => window.ssbvb.stats());
  frames.sort((a, b) => a - b);
  console.log(JSON.stringify({ q, title, prepare_ms: s.prepare_ms, first_frame_ms: s.first_frame_ms, frame_ms_median: frames[2], frames, passes: s.passes_gpu_ms }));
  await page.close();
}
await browser.close();
