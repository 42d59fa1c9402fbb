// The page's voxelizing worker (crates/web/src/worker.rs): prepares a model off the page's
// thread. In: {name, bytes, level}. Out: {stage, done, total} as it goes, {warning} for
// each thing its load could not do, then {asset} (the prepared asset's bytes) or {error}.
import init, { prepare_model_in_worker } from "./pkg/ssbvb_web.js";

const ready = init();

self.onmessage = async (e) => {
  const { name, bytes, level } = e.data;
  try {
    await ready;
    const asset = prepare_model_in_worker(name, bytes, level);
    self.postMessage({ asset }, [asset.buffer]);
  } catch (err) {
    self.postMessage({ error: String(err && err.message ? err.message : err) });
  }
};
