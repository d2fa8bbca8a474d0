// The worker: builds worlds with the engine's own code (its WebAssembly, instantiated here too)
// and sends them to the page as layers whose buffers are transferred, not copied.
import init, { generate_world, heightmap_world } from './pkg/rayterra_web.js';

const ready = init();

self.onmessage = async ({ data }) => {
  try {
    await ready;
    const progress = (fraction, stage) => self.postMessage({ type: 'progress', fraction, stage });
    let layers;
    let description;
    if (data.type === 'generate') {
      layers = generate_world(data.seed, data.grid, progress);
      description = `procedural island, seed ${data.seed}, ${data.grid}x${data.grid}`;
    } else {
      layers = heightmap_world(new Uint8Array(data.bytes), data.name, data.seed, progress);
      const heightmap = layers.find((layer) => layer.name === 'heightmap');
      description = `heightmap ${data.name}, ${heightmap.width}x${heightmap.height}`;
    }
    self.postMessage({ type: 'world', layers, description }, layers.map((layer) => layer.data.buffer));
  } catch (error) {
    self.postMessage({ type: 'error', message: error?.message ?? String(error) });
  }
};
