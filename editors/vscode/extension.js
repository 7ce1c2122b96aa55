// Starts the `simit` debug type's adapter from the `simit.path` setting (plain JavaScript, no
// build step). package.json's runtime/runtimeArgs ("simit dap" from PATH) is the default that
// VS Code uses by itself; a setting can only reach the adapter's command line through code.
'use strict';
const path = require('path');
const vscode = require('vscode');

function simit_executable() {
  const setting = vscode.workspace.getConfiguration('simit').get('path') || 'simit';
  // A bare name is looked up on PATH; a relative path is taken from the first workspace folder.
  if (path.isAbsolute(setting) || !/[\\/]/.test(setting)) return setting;
  const folder = vscode.workspace.workspaceFolders?.[0];
  return folder ? path.join(folder.uri.fsPath, setting) : setting;
}

function activate(context) {
  context.subscriptions.push(vscode.debug.registerDebugAdapterDescriptorFactory('simit', {
    createDebugAdapterDescriptor(session) {
      const cwd = session.workspaceFolder?.uri.fsPath;
      return new vscode.DebugAdapterExecutable(simit_executable(), ['dap'], cwd ? {cwd} : {});
    },
  }));
}

function deactivate() {}

module.exports = {
  activate,
  deactivate
};
