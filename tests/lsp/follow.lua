-- For tests/window.rs: Neovim's LSP client on $ROL_FILE turns the
-- red sphere blue without saving, then breaks the text, then quits
-- without saving; a few seconds between, for screenshots.
local id = vim.lsp.start_client({ name = 'rayoflight', cmd = { os.getenv('ROL_BIN'), 'lsp' }, root_dir = vim.fn.getcwd() })
vim.cmd('edit ' .. os.getenv('ROL_FILE'))
local buf = vim.api.nvim_get_current_buf()
vim.lsp.buf_attach_client(buf, id)
vim.wait(5000, function() local c = vim.lsp.get_client_by_id(id); return c ~= nil and c.initialized == true end, 20)
local line = tonumber(os.getenv('ROL_LINE'))
vim.api.nvim_buf_set_lines(buf, line, line + 1, false, { '    <color red="0" green="0" blue="1"/>' })
vim.wait(4000, function() return false end, 50)
vim.api.nvim_buf_set_lines(buf, line, line + 1, false, { '    <color red="0" green="0" blue="-1"/>' })
vim.wait(4000, function() return false end, 50)
vim.cmd('qa!')
