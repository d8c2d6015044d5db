// The VS Code client of `tsfc lsp`: starts the server over stdio for .tsf files.
'use strict';

const vscode = require('vscode');
const { LanguageClient, TransportKind } = require('vscode-languageclient/node');

let client;

function activate(context) {
  const command = vscode.workspace.getConfiguration('tsfc').get('path', 'tsfc');
  const server = { command, args: ['lsp'], transport: TransportKind.stdio };
  client = new LanguageClient(
    'tsfc',
    'tsfc language server',
    { run: server, debug: server },
    { documentSelector: [{ scheme: 'file', language: 'tsf' }] }
  );
  context.subscriptions.push({ dispose: () => client && client.stop() });
  return client.start();
}

function deactivate() {
  return client ? client.stop() : undefined;
}

module.exports = { activate, deactivate };
