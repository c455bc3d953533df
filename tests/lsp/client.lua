-- A real LSP client for tests/desktop/lsp.rs: Neovim's own (0.7 and later),
-- headless, on the scene s.xml of the current folder. It types an error
-- after non-ASCII text, waits for the diagnostic, fixes it, asks for
-- completion, hover and symbols, and writes what it got as JSON to
-- $ROL_OUT. The server is $ROL_BIN lsp.
local out = {}
local bin = os.getenv('ROL_BIN')
local id = vim.lsp.start_client({ name = 'rayoflight', cmd = { bin, 'lsp' }, root_dir = vim.fn.getcwd() })
vim.cmd('edit s.xml')
local buf = vim.api.nvim_get_current_buf()
vim.lsp.buf_attach_client(buf, id)
local ok = vim.wait(5000, function()
  local c = vim.lsp.get_client_by_id(id)
  return c ~= nil and c.initialized == true
end, 20)
out.initialized = ok
local c = vim.lsp.get_client_by_id(id)
out.encoding = c.offset_encoding
out.server_encoding = c.server_capabilities and c.server_capabilities.positionEncoding
-- an error after non-ASCII text, typed into the buffer
vim.api.nvim_buf_set_lines(buf, 4, 5, false, { ' <!-- é😀 --><material ka="-1" kd="0.3" ks="0.3" m="20"/>' })
out.got_diag = vim.wait(5000, function() return #vim.diagnostic.get(buf) > 0 end, 20)
local d = vim.diagnostic.get(buf)[1]
if d then out.diag = { lnum = d.lnum, col = d.col, end_col = d.end_col, message = d.message } end
-- fixed: the error goes
vim.api.nvim_buf_set_lines(buf, 4, 5, false, { ' <material ka="0.3" kd="0.3" ks="0.3" m="20"/>' })
out.cleared = vim.wait(5000, function() return #vim.diagnostic.get(buf) == 0 end, 20)
local uri = vim.uri_from_bufnr(buf)
local function request(method, line, character)
  local r = vim.lsp.buf_request_sync(buf, method, { textDocument = { uri = uri }, position = { line = line, character = character } }, 5000)
  return r and r[id] and r[id].result
end
-- completion of attributes inside <material ...> on line 5 (0-based 4), before ka
local comp = request('textDocument/completion', 4, 11)
out.completion = {}
if comp then for _, item in ipairs(comp.items or comp) do table.insert(out.completion, item.label) end end
local h = request('textDocument/hover', 4, 12)
out.hover = h and h.contents and (h.contents.value or h.contents)
local sym = vim.lsp.buf_request_sync(buf, 'textDocument/documentSymbol', { textDocument = { uri = uri } }, 5000)
out.symbols = {}
if sym and sym[id] and sym[id].result then for _, s in ipairs(sym[id].result) do table.insert(out.symbols, s.name .. '@' .. s.range.start.line) end end
local f = io.open(os.getenv('ROL_OUT'), 'w')
f:write(vim.fn.json_encode(out))
f:close()
vim.lsp.stop_client(id)
vim.wait(1000, function() return vim.lsp.get_client_by_id(id) == nil end, 20)
vim.cmd('qa!')
