-- For tests/desktop/lsp.rs: Neovim's LSP client on s.xml changes a value without
-- saving, waits, then saves (:write) and quits. The server is $ROL_BIN lsp.
local id = vim.lsp.start_client({ name = 'rayoflight', cmd = { os.getenv('ROL_BIN'), 'lsp' }, root_dir = vim.fn.getcwd() })
vim.cmd('edit s.xml')
local buf = vim.api.nvim_get_current_buf()
vim.lsp.buf_attach_client(buf, id)
vim.wait(5000, function() local c = vim.lsp.get_client_by_id(id); return c ~= nil and c.initialized == true end, 20)
vim.api.nvim_buf_set_lines(buf, 4, 5, false, { ' <material ka="0.9" kd="0.3" ks="0.3" m="20"/>' })
vim.wait(1500, function() return false end, 50)
vim.cmd('write')
vim.wait(1000, function() return false end, 50)
vim.lsp.stop_client(id)
vim.wait(1000, function() return vim.lsp.get_client_by_id(id) == nil end, 20)
vim.cmd('qa!')
