// Starts `mcl2pnml lsp` for every .mcl file (docs/editors.md).
const vscode = require("vscode");
const { LanguageClient } = require("vscode-languageclient/node");

let client;

function activate(context) {
  const [command, ...args] = vscode.workspace.getConfiguration("mcl").get("server.command");
  client = new LanguageClient(
    "mcl2pnml", "MCL (mcl2pnml)",
    { command, args },
    { documentSelector: [{ language: "mcl" }] });
  context.subscriptions.push(client);
  return client.start();
}

function deactivate() {
  return client ? client.stop() : undefined;
}

module.exports = { activate, deactivate };
