// The worker: builds worlds with the engine's own code (its WebAssembly, instantiated here too)
// and sends them to the page as layers whose buffers are transferred, not copied.
import init, { generate_world, heightmap_world } from './pkg/rayterra_web.js';

const ready = init();

self.onmessage = async ({ data }) => {
  try {
    await ready;
    const progress = (fraction, stage) => self.postMessage({ type: 'progress', fraction, stage });
    // The world's layers (its scene's numbers among them: elevation data brings its own sea,
    // height mapping and camera start) and the page's line about it.
    const { layers, description } = data.type === 'generate'
      ? generate_world(data.seed, data.grid, progress)
      : heightmap_world(new Uint8Array(data.bytes), data.name, data.query, progress);
    self.postMessage({ type: 'world', layers, description }, layers.map((layer) => layer.data.buffer));
  } catch (error) {
    self.postMessage({ type: 'error', message: error?.message ?? String(error) });
  }
};
