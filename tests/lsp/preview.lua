-- For tests/window.rs: Neovim set up by the README's init.lua (given with
-- -u) opens $ROL_FILE, turns its red sphere blue without saving, runs
-- :RayOfLightPreview, and waits $ROL_WAIT ms (the app starts and shows
-- the buffer meanwhile); then quits without saving.
vim.cmd('edit ' .. os.getenv('ROL_FILE'))
local buf = vim.api.nvim_get_current_buf()
vim.wait(5000, function()
  for _, c in pairs(vim.lsp.buf_get_clients(buf)) do
    if c.initialized then return true end
  end
  return false
end, 20)
local line = tonumber(os.getenv('ROL_LINE'))
vim.api.nvim_buf_set_lines(buf, line, line + 1, false, { '    <color red="0" green="0" blue="1"/>' })
vim.cmd('RayOfLightPreview')
vim.wait(tonumber(os.getenv('ROL_WAIT')), function() return false end, 50)
vim.cmd('qa!')
