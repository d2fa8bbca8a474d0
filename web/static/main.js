// The page: starts the engine (WebAssembly) on the canvas, has the worker build the world
// (so the page never freezes) and hands it over, and loads heightmap files picked or dropped:
// elevation data (GeoTIFF, SRTM .hgt, Esri ASCII grid, OpenEXR) or greyscale images.
import init, { start, deliver_world, page_state, capture } from './pkg/rayterra_web.js';

const $ = (id) => document.getElementById(id);

// An error stays on the page until the user acts (picks or drops another heightmap); once the
// engine has stopped (no GPU, an internal error: `page_state().error`), its message stays for good.
function showError(message) {
  const box = $('error');
  box.textContent = message;
  box.hidden = false;
  $('progress').hidden = true;
}

function showProgress(fraction, stage) {
  $('progress').hidden = false;
  $('progress-bar').value = fraction;
  $('progress-text').textContent = `building the world: ${stage} ${Math.round(fraction * 100)}%`;
}

async function main() {
  try {
    await init();
  } catch (error) {
    $('api').textContent = 'not started: this browser cannot run the page (see below)';
    showError(`This browser cannot run the page's WebAssembly: ${error}`);
    return;
  }
  // For people and for the browser test: what the page is doing, the next frame read back, and
  // how many worlds the worker has finished.
  window.rayterra = { state: page_state, capture, worldsBuilt: 0 };
  const stopped = () => page_state().error != null;
  let options;
  try {
    const query = new URLSearchParams(location.search);
    const size = query.get('size');
    if (size) {
      // A fixed canvas size (e.g. to compare with `rayterra terrain --screenshot --size`).
      const [width, height] = size.split(/x/i).map(Number);
      if (width > 0 && height > 0) {
        const canvas = $('terrain');
        canvas.classList.add('fixed');
        canvas.style.width = `${width / devicePixelRatio}px`;
        canvas.style.height = `${height / devicePixelRatio}px`;
      }
    }
    options = start(location.search);
  } catch (error) {
    $('api').textContent = 'not started: the address has an error (see below)';
    showError(error.message ?? String(error));
    return;
  }

  const worker = new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
  let building = false;
  worker.onmessage = ({ data }) => {
    if (data.type !== 'progress') building = false;
    if (data.type === 'world') window.rayterra.worldsBuilt += 1;
    // A stopped engine draws nothing more: its message stays, without progress over it.
    if (stopped()) return;
    switch (data.type) {
      case 'progress':
        showProgress(data.fraction, data.stage);
        break;
      case 'world':
        try {
          deliver_world(data.layers, data.description);
          $('progress').hidden = true;
        } catch (error) {
          showError(error.message ?? String(error));
        }
        break;
      case 'error':
        showError(data.message);
        break;
    }
  };
  worker.onerror = (event) => {
    building = false;
    if (stopped()) return;
    showError(`The world could not be built: ${event.message ?? 'the worker stopped'}`);
  };
  const build = (message, transfer = []) => {
    if (stopped()) return;
    if (building) {
      showError('A world is still being built; try again when it is done.');
      return;
    }
    building = true;
    $('error').hidden = true;
    showProgress(0, 'starting');
    worker.postMessage(message, transfer);
  };
  build({ type: 'generate', seed: options.seed, grid: options.grid });

  const load = async (file) => {
    if (!file) return;
    const bytes = await file.arrayBuffer();
    // The address's seed and elevation options (water-level, ...) go with it.
    build({ type: 'heightmap', name: file.name, bytes, query: location.search }, [bytes]);
  };
  $('file').addEventListener('change', (event) => load(event.target.files[0]));
  // A heightmap or elevation file dropped anywhere on the page.
  const hud = $('hud');
  document.body.addEventListener('dragover', (event) => {
    event.preventDefault();
    hud.classList.add('dropping');
  });
  document.body.addEventListener('dragleave', () => hud.classList.remove('dropping'));
  document.body.addEventListener('drop', (event) => {
    event.preventDefault();
    hud.classList.remove('dropping');
    load(event.dataTransfer.files[0]);
  });
}

main();
