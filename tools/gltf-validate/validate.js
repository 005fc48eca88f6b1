#!/usr/bin/env node
// fp-gltf-validate FILE.gltf|FILE.glb [--json]: the Khronos glTF-Validator's report on one
// file (npm package gltf-validator). Prints one summary line (errors, warnings, infos,
// hints, and every message with its code and JSON pointer), or the whole report as JSON with
// --json. Exit status: 0 no errors and no warnings, 1 errors or warnings, 2 usage or I/O.
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

const args = process.argv.slice(2);
const json = args.includes('--json');
const files = args.filter((a) => a !== '--json');
if (files.length !== 1) {
  process.stderr.write('usage: fp-gltf-validate FILE.gltf|FILE.glb [--json]\n');
  process.exit(2);
}
const file = files[0];
let data;
try {
  data = new Uint8Array(fs.readFileSync(file));
} catch (e) {
  process.stderr.write(`fp-gltf-validate: ${file}: ${e.message}\n`);
  process.exit(2);
}
const dir = path.dirname(file);
validator.validateBytes(data, {
  uri: path.basename(file),
  maxIssues: 0,
  externalResourceFunction: (uri) => new Promise((resolve, reject) => {
    // relative resources only, inside the file's folder
    const p = path.resolve(dir, decodeURIComponent(uri));
    if (!p.startsWith(path.resolve(dir) + path.sep)) return reject(new Error('outside folder'));
    fs.readFile(p, (err, d) => (err ? reject(err) : resolve(new Uint8Array(d))));
  }),
}).then((report) => {
  const i = report.issues;
  if (json) {
    process.stdout.write(JSON.stringify(report, null, 2) + '\n');
  } else {
    process.stdout.write(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ` +
      `${i.numInfos} infos, ${i.numHints} hints (glTF-Validator ${report.validatorVersion})\n`);
    const sev = ['error', 'warning', 'info', 'hint'];
    for (const m of i.messages)
      process.stdout.write(`  ${sev[m.severity] || m.severity} ${m.code} ${m.pointer || ''}: ${m.message}\n`);
  }
  process.exit(i.numErrors === 0 && i.numWarnings === 0 ? 0 : 1);
}, (err) => {
  process.stderr.write(`fp-gltf-validate: ${file}: ${err}\n`);
  process.exit(2);
});
