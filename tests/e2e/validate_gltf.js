// Validates a .glb or .gltf with the Khronos glTF validator (npm package gltf-validator).
//   node validate_gltf.js FILE
// Prints the report's issue summary (and every error/warning) as JSON on stdout.
// Exit: 0 valid (no errors; warnings allowed unless MEBAKE_GLTF_STRICT=1), 1 invalid,
// 2 usage or unreadable file, 77 the gltf-validator package is not installed (skip).
// The package is found through NODE_PATH or the usual node_modules lookup, e.g.
//   (cd build/gltfv && npm install gltf-validator); NODE_PATH=build/gltfv/node_modules node ...
'use strict';

const fs = require('fs');

let validator;
try {
    validator = require('gltf-validator');
} catch (e) {
    console.error('gltf-validator is not installed');
    process.exit(77);
}

const file = process.argv[2];
if (!file) {
    console.error('usage: node validate_gltf.js FILE');
    process.exit(2);
}
let bytes;
try {
    bytes = new Uint8Array(fs.readFileSync(file));
} catch (e) {
    console.error(`cannot read ${file}: ${e.message}`);
    process.exit(2);
}

validator.validateBytes(bytes, {maxIssues: 100})
    .then((report) => {
        const issues = report.issues;
        const shown = issues.messages.filter((m) => m.severity <= 1);
        console.log(JSON.stringify({
            numErrors: issues.numErrors,
            numWarnings: issues.numWarnings,
            numInfos: issues.numInfos,
            messages: shown,
        }, null, 2));
        const strict = process.env.MEBAKE_GLTF_STRICT === '1';
        process.exit(issues.numErrors > 0 || (strict && issues.numWarnings > 0) ? 1 : 0);
    })
    .catch((e) => {
        console.error(`validation failed: ${e}`);
        process.exit(1);
    });
