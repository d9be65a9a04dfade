// Validates glTF binaries with the Khronos glTF validator (npm package gltf-validator).
// Usage: NODE_PATH=<its node_modules> node .ci/validate_gltf.js FILE.glb...
// Prints each file's counts and error messages; exits 1 if any file has an error.
const fs = require("fs");
const validator = require("gltf-validator");

(async () => {
  let failed = false;
  for (const file of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)));
    const { numErrors, numWarnings } = report.issues;
    console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings (validator ${validator.version()})`);
    for (const m of report.issues.messages.filter((m) => m.severity === 0)) {
      console.log(`  ${m.code} at ${m.pointer || "-"}: ${m.message}`);
    }
    failed = failed || numErrors > 0;
  }
  process.exit(failed ? 1 : 0);
})().catch((e) => {
  console.error(e);
  process.exit(2);
});
