// Bundles the page (src/ with three.js) into one classic script, dist/viewer.js, and copies
// viewer.html beside it: classic scripts load from file://, ES modules do not.
// Usage: node build.mjs OUT_DIR MODEL...   (the models whose wasm/wlx_<model>.js the CMake build makes)
import * as esbuild from 'esbuild';
import { copyFileSync, mkdirSync, renameSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const [outDir, ...models] = process.argv.slice(2);
if (!outDir || models.length === 0 || models.some((m) => !/^[a-z][a-z0-9_]*$/.test(m))) {
  console.error('usage: node build.mjs OUT_DIR MODEL... (model names: lower-case letters, digits, _)');
  process.exit(2);
}
mkdirSync(outDir, { recursive: true });
// Written under temporary names and renamed into place, so a file under its own name is complete.
await esbuild.build({
  entryPoints: [join(here, 'src/main.js')],
  bundle: true,
  format: 'iife',
  target: 'es2020',
  minify: true,
  legalComments: 'eof',  // keeps three.js' licence notice
  banner: { js: `window.WLX_VIEWER_MODELS = ${JSON.stringify(models)};` },
  outfile: join(outDir, 'viewer.js.tmp'),
  logLevel: 'warning',
});
renameSync(join(outDir, 'viewer.js.tmp'), join(outDir, 'viewer.js'));
copyFileSync(join(here, 'viewer.html'), join(outDir, 'viewer.html.tmp'));
renameSync(join(outDir, 'viewer.html.tmp'), join(outDir, 'viewer.html'));
