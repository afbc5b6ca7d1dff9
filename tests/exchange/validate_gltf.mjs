// Run the Khronos glTF validator (npm gltf-validator, from node_modules) on files; print one JSON report line each.
// Usage: node validate_gltf.mjs FILE.glb [FILE.glb ...]
import fs from "fs";
import { createRequire } from "module";

const require = createRequire(process.cwd() + "/");
const validator = require("gltf-validator");
for (const path of process.argv.slice(2)) {
  const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(path)), { maxIssues: 100 });
  const issues = report.issues;
  console.log(JSON.stringify({
    path,
    errors: issues.numErrors,
    warnings: issues.numWarnings,
    messages: issues.messages.filter((m) => m.severity <= 1),
    info: report.info,
  }));
}
