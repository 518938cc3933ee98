// Validates glTF/GLB files with Khronos' glTF validator (installed in .tools/ by
// scripts/install-deps.sh). Prints one line per file; exits 1 if any has an error.
// usage: node scripts/validate-gltf.mjs FILE...
import { createRequire } from 'module';
import fs from 'fs';
import path from 'path';
import { fileURLToPath } from 'url';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const require = createRequire(path.join(root, '.tools', 'package.json'));
const validator = require('gltf-validator');

let failed = 0;
for (const file of process.argv.slice(2)) {
  const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: file,
    externalResourceFunction: (uri) => {
      try {
        return Promise.resolve(new Uint8Array(fs.readFileSync(path.join(path.dirname(file), decodeURIComponent(uri)))));
      } catch (e) {
        return Promise.reject(e.message);  // reported by the validator as an error of this file
      }
    },
  });
  const i = report.issues;
  console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos`);
  for (const m of i.messages.filter((m) => m.severity === 0).slice(0, 10)) console.log(`  ${m.code}: ${m.message} (${m.pointer || ''})`);
  if (i.numErrors > 0) failed++;
}
process.exit(failed ? 1 : 0);
