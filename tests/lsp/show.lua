-- For tests/desktop/lsp.rs and tests/window.rs: Neovim's LSP client on
-- $ROL_FILE, saying it shows documents when a server asks
-- (window/showDocument: Neovim 0.8 and later have this handler; 0.7 needs
-- it given, as here). It puts the cursor on line $ROL_CURSOR_LINE
-- (0-based), column 4, and asks for highlights there as editors do when
-- the cursor moves, records the
-- answer, then waits until a server asks it to show a document, does so
-- (cursor on the selection's start), moves the cursor out of every element
-- when $ROL_LEAVE_LINE is set, and records the requests and answers as
-- JSON to $ROL_OUT; then quits.
local out = {}
local handlers = {
  ['window/showDocument'] = function(_, result, ctx)
    out.show = result
    local client = vim.lsp.get_client_by_id(ctx.client_id)
    vim.lsp.util.jump_to_location({ uri = result.uri, range = result.selection }, client.offset_encoding)
    out.cursor_after_show = vim.api.nvim_win_get_cursor(0)
    return { success = true }
  end,
}
local capabilities = vim.lsp.protocol.make_client_capabilities()
capabilities.window.showDocument = { support = true }
local id = vim.lsp.start_client({
  name = 'rayoflight',
  cmd = { os.getenv('ROL_BIN'), 'lsp' },
  root_dir = vim.fn.getcwd(),
  capabilities = capabilities,
  handlers = handlers,
})
vim.cmd('edit ' .. os.getenv('ROL_FILE'))
local buf = vim.api.nvim_get_current_buf()
vim.lsp.buf_attach_client(buf, id)
out.initialized = vim.wait(5000, function()
  local c = vim.lsp.get_client_by_id(id)
  return c ~= nil and c.initialized == true
end, 20)
-- Time for the server to find the app and hand it the text.
vim.wait(tonumber(os.getenv('ROL_SETTLE') or '1500'), function() return false end, 50)
vim.api.nvim_win_set_cursor(0, { tonumber(os.getenv('ROL_CURSOR_LINE')) + 1, 4 })
local r = vim.lsp.buf_request_sync(buf, 'textDocument/documentHighlight', vim.lsp.util.make_position_params(), 5000)
for _, answer in pairs(r or {}) do out.highlight = answer.result end
out.shown = vim.wait(tonumber(os.getenv('ROL_WAIT_SHOW') or '10000'), function() return out.show ~= nil end, 20)
-- Then, if asked, the cursor leaves to line $ROL_LEAVE_LINE (0-based),
-- in no object's element, and asks for highlights there.
if os.getenv('ROL_LEAVE_LINE') then
  vim.api.nvim_win_set_cursor(0, { tonumber(os.getenv('ROL_LEAVE_LINE')) + 1, 2 })
  local left = vim.lsp.buf_request_sync(buf, 'textDocument/documentHighlight', vim.lsp.util.make_position_params(), 5000)
  for _, answer in pairs(left or {}) do out.left_highlight = answer.result end
  -- Time for the server to tell the app.
  vim.wait(300, function() return false end, 50)
end
local f = io.open(os.getenv('ROL_OUT') .. '.part', 'w')
f:write(vim.fn.json_encode(out))
f:close()
os.rename(os.getenv('ROL_OUT') .. '.part', os.getenv('ROL_OUT'))
vim.cmd('qa!')
