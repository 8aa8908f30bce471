-- Neovim's built-in LSP client starts `arbiter lsp` on a broken copy of the soccer config and
-- reads the diagnostic back. Run headless by nvim_test.sh, which passes ARBITER and CONFIG in the
-- environment. Exits 0 when the expected diagnostic arrived, 1 otherwise. Written for Debian's
-- Neovim 0.7 (vim.lsp.start_client; vim.lsp.start came in 0.8).
local arbiter, config = os.getenv('ARBITER'), os.getenv('CONFIG')

local function fail(message)
  io.stderr:write('nvim_test: ' .. message .. '\n')
  os.exit(1)
end

vim.cmd('edit ' .. vim.fn.fnameescape(config))
local buffer = vim.api.nvim_get_current_buf()
local client = vim.lsp.start_client({ name = 'arbiter', cmd = { arbiter, 'lsp' },
  root_dir = vim.fn.fnamemodify(config, ':h') })
if not client then fail('the client did not start') end
vim.lsp.buf_attach_client(buffer, client)

local found = vim.wait(10000, function()
  return #vim.diagnostic.get(buffer) > 0
end, 50)
if not found then fail('no diagnostic within 10 s') end

local diagnostic = vim.diagnostic.get(buffer)[1]
local line = vim.api.nvim_buf_get_lines(buffer, diagnostic.lnum, diagnostic.lnum + 1, false)[1]
local text = line:sub(diagnostic.col + 1, diagnostic.end_col)
io.stdout:write(string.format('%s:%d:%d: %s [%s] %s\n', config, diagnostic.lnum + 1, diagnostic.col + 1,
  diagnostic.message, diagnostic.code, text))
if diagnostic.code ~= 'unknown-behaviour' then fail('unexpected code ' .. tostring(diagnostic.code)) end
if text ~= 'kick_bal' then fail("the range covers '" .. text .. "', not 'kick_bal'") end
if diagnostic.source ~= 'arbiter' then fail('unexpected source ' .. tostring(diagnostic.source)) end
vim.lsp.stop_client(client)
os.exit(0)
