#!/usr/bin/env bash
# The editor screenshot of docs/reference/scenario-format.md ("In your editor and in CI"), made with
# real programs: Neovim's built-in LSP client (no plugins) talking to the YAML language server from
# npm, in an xterm on a virtual X display, captured with ImageMagick's `import`. The scenario has
# six mistakes; after the server has checked it, the script asks for completion under `simulation:`
# (Ctrl-X Ctrl-O, as a user would) and takes the picture.
#
#   apt-get install neovim xvfb xterm imagemagick fonts-dejavu-core     (Debian 12: Neovim 0.7)
#   bash benchmarks/make_editor_picture.sh [docs/pictures/editor-schema.png]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:-$root/docs/pictures/editor-schema.png}"
work="$(mktemp -d)"
trap 'kill "${xterm_pid:-}" "${xvfb_pid:-}" 2>/dev/null || true; rm -rf "$work"' EXIT

(cd "$work" && npm install --silent --no-audit --no-fund yaml-language-server@2 >/dev/null)
mkdir -p "$work/project/scenarios" "$work/project/.navscenario"
touch "$work/project/pyproject.toml"
PYTHONPATH="$root" python -c "import sys; from pytest_navscenario.cli.main import main; sys.exit(main(sys.argv[1:]))" \
  schema -o "$work/project/.navscenario/scenario-v1.json" >/dev/null
cat > "$work/project/scenarios/demo.yaml" <<'EOF'
# yaml-language-server: $schema=../.navscenario/scenario-v1.json
version: 1
robot:
  drive: differential
  lidar:
    beams: 0
    rang_max: 8
mission:
  start: {x: 0, y: 0, yaw: 90}
  goal: {x: 0, y: 10, yaw: 90}
obstacles:
  - {type: box, x: 3, y: 5, length: -1, width: 1}
  - type: cylinder
    x: 2
    y: 2
    radius: 0.5
    yaw: 30
search:
  motion_speed: [0.5, -0.5]
simulation:
  timestep: 0.01
  
EOF
cat > "$work/init.lua" <<EOF
vim.opt.number = true
vim.opt.signcolumn = 'yes'
vim.opt.termguicolors = true
vim.opt.completeopt = {'menuone', 'noinsert'}
vim.opt.shortmess:append('c')
vim.cmd('syntax on')
vim.diagnostic.config({virtual_text = {prefix = '■'}, signs = true, underline = true, severity_sort = true})
vim.api.nvim_create_autocmd('FileType', {pattern = 'yaml', callback = function()
  local id = vim.lsp.start_client({
    name = 'yamlls',
    cmd = {'$work/node_modules/.bin/yaml-language-server', '--stdio'},
    root_dir = '$work/project',
    settings = {yaml = {validate = true, hover = true, completion = true, schemaStore = {enable = false}}},
  })
  vim.lsp.buf_attach_client(0, id)
  vim.bo.omnifunc = 'v:lua.vim.lsp.omnifunc'
end})
vim.defer_fn(function()
  vim.api.nvim_win_set_cursor(0, {22, 2})
  vim.api.nvim_feedkeys(vim.api.nvim_replace_termcodes('A<C-x><C-o>', true, false, true), 'n', false)
end, 9000)
EOF
display=":$((70 + RANDOM % 20))"
Xvfb "$display" -screen 0 1000x620x24 >/dev/null 2>&1 & xvfb_pid=$!
sleep 2
DISPLAY="$display" xterm -geometry 112x34+0+0 -fa 'DejaVu Sans Mono' -fs 10.5 -bg '#1e1e1e' -fg '#d4d4d4' \
  -e sh -c "cd '$work/project' && TERM=xterm-256color exec nvim -u '$work/init.lua' scenarios/demo.yaml" & xterm_pid=$!
sleep 14
DISPLAY="$display" import -window root "$out"
echo "wrote $out"
