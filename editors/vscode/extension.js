// Starts `arbiter lsp` for the YAML and JSON files of a workspace that are Arbiter configs (those
// that start with `arbiter:` or carry it as a top-level key; the server ignores nothing else, so
// the selector keeps it away from other YAML and JSON).
const vscode = require('vscode');
const { LanguageClient } = require('vscode-languageclient/node');

let client;

function activate(context) {
  const settings = vscode.workspace.getConfiguration('arbiter');
  const args = [];
  for (const dir of settings.get('pluginPath', [])) args.push('--plugin-path', dir);
  args.push('lsp');
  const command = settings.get('path', 'arbiter');
  client = new LanguageClient('arbiter', 'Arbiter',
    { run: { command, args }, debug: { command, args } },
    {
      documentSelector: [
        { scheme: 'file', language: 'yaml', pattern: '**/configs/**' },
        { scheme: 'file', language: 'json', pattern: '**/configs/**' },
        { scheme: 'file', pattern: '**/*.arbiter.{yaml,yml,json}' },
      ],
    });
  context.subscriptions.push(client);
  return client.start();
}

function deactivate() {
  return client ? client.stop() : undefined;
}

module.exports = { activate, deactivate };
