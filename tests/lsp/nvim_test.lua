-- Neovim's built-in LSP client and `arbiter lsp`, run headless by nvim_test.sh in a project folder
-- (PROJECT) of configs and other files. MODE=docs: the set-up of docs/editors.md was loaded
-- before this file and attaches the server to every YAML and JSON buffer; MODE=help: the
-- HELP_COMMAND of `arbiter lsp --help` is run in one config's buffer. Exits 0 when every
-- expectation held, 1 otherwise. Runs on Debian's Neovim 0.7 as on later ones.
local project, mode = os.getenv('PROJECT'), os.getenv('MODE')

local function fail(message)
  io.stderr:write('nvim_test (' .. mode .. '): ' .. message .. '\n')
  os.exit(1)
end

local function open(name)
  vim.cmd('edit ' .. vim.fn.fnameescape(project .. '/' .. name))
  return vim.api.nvim_get_current_buf()
end

local function wait_for(buffer, count, what)
  local ok = vim.wait(15000, function()
    return #vim.diagnostic.get(buffer) >= count
  end, 50)
  if not ok then
    fail(string.format('%s: %d diagnostic(s) within 15 s, expected %d', what,
      #vim.diagnostic.get(buffer), count))
  end
  return vim.diagnostic.get(buffer)
end

-- The server answers requests in order and publishes as it goes, and the client handles its
-- messages in the order they came: once the answer to a request is in, every list published
-- for what was sent before it has been taken in. (A wait of a fixed time proves nothing on a
-- loaded machine.)
local function settle(buffer, what)
  local params = { textDocument = vim.lsp.util.make_text_document_params(buffer) }
  local answers = vim.lsp.buf_request_sync(buffer, 'textDocument/documentSymbol', params, 15000)
  if not answers or vim.tbl_isempty(answers) then
    fail(what .. ': no answer to a request within 15 s')
  end
end

local function text_of(buffer, diagnostic)
  local line = vim.api.nvim_buf_get_lines(buffer, diagnostic.lnum, diagnostic.lnum + 1, false)[1]
  return line:sub(diagnostic.col + 1, diagnostic.end_col)
end

local function expect_one(buffer, what, code, text)
  wait_for(buffer, 1, what)
  settle(buffer, what)
  local diagnostics = vim.diagnostic.get(buffer)
  for _, d in ipairs(diagnostics) do
    io.stdout:write(string.format('%s:%d:%d: %s [%s] %s\n', what, d.lnum + 1, d.col + 1, d.message,
      d.code, text_of(buffer, d)))
  end
  if #diagnostics ~= 1 then fail(what .. ': ' .. #diagnostics .. ' diagnostics, expected 1') end
  local d = diagnostics[1]
  if d.code ~= code then fail(what .. ': code ' .. tostring(d.code) .. ', expected ' .. code) end
  if text_of(buffer, d) ~= text then
    fail(what .. ": the range covers '" .. text_of(buffer, d) .. "', not '" .. text .. "'")
  end
  if d.source ~= 'arbiter' then fail(what .. ': source ' .. tostring(d.source)) end
end

if mode == 'help' then
  local buffer = open('walk_and_kick.yaml')
  vim.cmd(os.getenv('HELP_COMMAND'))
  expect_one(buffer, 'walk_and_kick.yaml', 'unknown-behaviour', 'kick_bal')
  os.exit(0)
end

-- A misspelt inhibitor, at its name.
local broken = open('walk_and_kick.yaml')
expect_one(broken, 'walk_and_kick.yaml', 'unknown-behaviour', 'kick_bal')

-- A config without `plugins: [soccer]` does not know soccer's classes because another config
-- loaded them, and opening it leaves the first config's error alone.
local without = open('without_plugins.yaml')
wait_for(without, 5, 'without_plugins.yaml')
settle(without, 'without_plugins.yaml')
local unknown = vim.diagnostic.get(without)
for _, d in ipairs(unknown) do
  if d.code ~= 'unknown-class' then fail('without_plugins.yaml: code ' .. tostring(d.code)) end
end
if #vim.diagnostic.get(broken) ~= 1 then
  fail('walk_and_kick.yaml lost its error when another config was opened')
end

-- Files that are not Arbiter configs: the server is attached and says nothing.
local others = { open('package.json'), open('docker-compose.yaml') }
for _, buffer in ipairs(others) do
  if #vim.lsp.buf_get_clients(buffer) == 0 then fail('the server was not attached to every file') end
end

-- An included file opened on its own: checked through main.yaml, which includes it, so only its
-- real error shows (not the 'arbiter' and 'name' a root config would need).
local part = open('parts/part.yaml')
expect_one(part, 'parts/part.yaml', 'unknown-class', 'scriptd')

for _, buffer in ipairs(others) do
  if #vim.diagnostic.get(buffer) > 0 then
    fail(vim.api.nvim_buf_get_name(buffer) .. ' is not a config but got diagnostics')
  end
end

-- Opening, then closing, the config that includes it leaves the included file's error alone.
local main = open('main.yaml')
settle(main, 'main.yaml')
if #vim.diagnostic.get(main) ~= 0 then fail('main.yaml got the error of the open parts/part.yaml') end
expect_one(part, 'parts/part.yaml', 'unknown-class', 'scriptd')
vim.cmd('bwipeout ' .. main)
settle(part, 'parts/part.yaml')
expect_one(part, 'parts/part.yaml', 'unknown-class', 'scriptd')

-- An include cycle is an error on the root file, at the include that leads into it.
local root = open('cycle/root.yaml')
expect_one(root, 'cycle/root.yaml', 'include-cycle', 'a.yaml')

-- :lua vim.lsp.buf.rename() of a state that a scripted state plans in its append: renames it
-- there too: the saved file validates, and only the lines that name the state changed.
local plan = open('goalie_plan.yaml')
settle(plan, 'goalie_plan.yaml')
local before = vim.api.nvim_buf_get_lines(plan, 0, -1, false)
local declared = vim.fn.search('^      monitor_ball:', 'w')
if declared == 0 then fail('goalie_plan.yaml: no state monitor_ball') end
vim.api.nvim_win_set_cursor(0, { declared, 8 })
vim.lsp.buf.rename('watch_ball')
local renamed = vim.wait(15000, function()
  return vim.fn.search('^      - watch_ball$', 'nw') > 0
end, 50)
if not renamed then fail('goalie_plan.yaml: the rename was not applied within 15 s') end
local after = vim.api.nvim_buf_get_lines(plan, 0, -1, false)
if #after ~= #before then fail('goalie_plan.yaml: the rename added or removed lines') end
local changed = {}
for i, line in ipairs(before) do
  if after[i] ~= line then
    if after[i] ~= line:gsub('monitor_ball', 'watch_ball') then
      fail('goalie_plan.yaml:' .. i .. ': ' .. after[i])
    end
    table.insert(changed, i)
  end
end
if table.concat(changed, ',') ~= '24,28,33' then
  fail('goalie_plan.yaml: changed lines ' .. table.concat(changed, ','))
end
vim.cmd('write')
local output = vim.fn.system({ 'arbiter', 'validate', project .. '/goalie_plan.yaml' })
if vim.v.shell_error ~= 0 then fail('goalie_plan.yaml after the rename: ' .. output) end
settle(plan, 'goalie_plan.yaml')
if #vim.diagnostic.get(plan) ~= 0 then fail('goalie_plan.yaml: diagnostics after the rename') end

-- The graph operations as code actions, chosen from the list Neovim shows (vim.ui.select, here
-- answered by title): on a layer's name a behaviour of a class is added (its edit resolved when
-- chosen, codeAction/resolve); on a selection from one behaviour to another, an inhibition; on
-- a behaviour's declaration, a move (resolved too); a layer added and removed, a state machine
-- added.
local paper = open('paper.yaml')
settle(paper, 'paper.yaml')
local function choose(title)
  vim.ui.select = function(items, options, on_choice)
    for _, item in ipairs(items) do
      if options.format_item(item) == title then return on_choice(item) end
    end
    local titles = {}
    for _, item in ipairs(items) do table.insert(titles, options.format_item(item)) end
    fail('paper.yaml: no code action "' .. title .. '" in: ' .. table.concat(titles, ' | '))
  end
end
local function wait_line(pattern, what)
  if not vim.wait(15000, function() return vim.fn.search(pattern, 'nw') > 0 end, 50) then
    fail('paper.yaml: ' .. what .. ' was not applied within 15 s:\n' ..
      table.concat(vim.api.nvim_buf_get_lines(paper, 0, -1, false), '\n'))
  end
  settle(paper, 'paper.yaml')
end
vim.api.nvim_win_set_cursor(0, { vim.fn.search('^  - name: control$', 'w'), 10 })
choose("Add a behaviour of class 'scripted' to layer 'control'")
vim.lsp.buf.code_action()
wait_line('^      scripted: {type: scripted}$', 'the added behaviour')
local first = vim.fn.search('^      kick_ball:$', 'w')
local last = vim.fn.search('^      search_for_ball:$', 'w')
choose("Add the inhibition 'kick_ball -> search_for_ball'")
vim.lsp.buf.range_code_action(nil, { first, 6 }, { last, 20 })
wait_line('^      - kick_ball -> search_for_ball$', 'the added inhibition')
-- On the added behaviour's declaration, resolved when chosen: it moves above head_control.
vim.api.nvim_win_set_cursor(0, { vim.fn.search('^      scripted: {type: scripted}$', 'w'), 8 })
choose("Move the behaviour 'scripted' up")
vim.lsp.buf.code_action()
wait_line('^      scripted: {type: scripted}\\n      head_control:$', 'the moved behaviour')
-- On the top-level key `layers:`, a layer at the end; on its name, removed again; on `name:`, a
-- state machine.
vim.api.nvim_win_set_cursor(0, { vim.fn.search('^layers:$', 'w'), 2 })
choose('Add a layer at the end')
vim.lsp.buf.code_action()
wait_line('^  - name: layer$', 'the added layer')
vim.api.nvim_win_set_cursor(0, { vim.fn.search('^  - name: layer$', 'w'), 10 })
choose("Remove the layer 'layer'")
vim.lsp.buf.code_action()
if not vim.wait(15000, function() return vim.fn.search('^  - name: layer$', 'nw') == 0 end, 50) then
  fail('paper.yaml: the removed layer is still there after 15 s')
end
settle(paper, 'paper.yaml')
vim.api.nvim_win_set_cursor(0, { vim.fn.search('^name: ', 'w'), 1 })
choose('Add a state machine')
vim.lsp.buf.code_action()
wait_line('^  machine:$', 'the added state machine')
vim.cmd('write')
output = vim.fn.system({ 'arbiter', 'validate', project .. '/paper.yaml' })
if vim.v.shell_error ~= 0 then fail('paper.yaml after the code actions: ' .. output) end

-- <C-x><C-o> (vim.lsp.omnifunc) after `type: soccer.` replaces the dotted word the server says
-- it replaces: soccer.GoBehindBall, not soccer.soccer.GoBehindBall. The keys are typed once this
-- file has run, so the check polls on a timer.
vim.cmd('buffer ' .. broken)
vim.cmd('setlocal noswapfile')  -- the edit is not saved: no swap file for the next run to find
vim.bo.omnifunc = 'v:lua.vim.lsp.omnifunc'
local typed = vim.fn.search('kick_ball: {type: soccer.KickBall}', 'w')
if typed == 0 then fail('walk_and_kick.yaml: no kick_ball line') end
vim.api.nvim_buf_set_lines(broken, typed - 1, typed, false, { '      kick_ball: {type: soccer.}' })
settle(broken, 'walk_and_kick.yaml')
vim.api.nvim_win_set_cursor(0, { typed, 30 })
local deadline = vim.loop.now() + 15000
vim.loop.new_timer():start(100, 100, vim.schedule_wrap(function()
  local line = vim.api.nvim_buf_get_lines(broken, typed - 1, typed, false)[1]
  if line ~= '      kick_ball: {type: soccer.}' then
    if not line:match('^      kick_ball: {type: soccer%.%u%w+}$') then
      fail('completion after type: soccer. gave: ' .. line)
    end
    os.exit(0)
  end
  if vim.loop.now() > deadline then fail('no completion after type: soccer. within 15 s') end
end))
vim.api.nvim_feedkeys(vim.api.nvim_replace_termcodes('a<C-x><C-o>', true, false, true), 'n', false)
