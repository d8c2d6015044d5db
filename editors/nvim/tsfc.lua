-- Neovim configuration for .tsf specs: filetype, comments, and the tsfc
-- language server (`tsfc lsp`): diagnostics, hover, go to definition,
-- references, completion, outline and formatting. Works with Neovim 0.7
-- (Debian 12's package) and newer.
--
-- Install: copy this file to ~/.config/nvim/lua/tsfc.lua and add
--   require('tsfc').setup()            -- or .setup({ cmd = { '/path/to/tsfc', 'lsp' } })
-- to init.lua; copy syntax/tsf.vim to ~/.config/nvim/syntax/ for highlighting.
local M = {}

-- One client per Neovim session, shared by every .tsf buffer.
local client_id = nil

local function attach(buf, cmd)
  if vim.lsp.start then -- Neovim 0.8+
    vim.lsp.start({ name = 'tsfc', cmd = cmd, root_dir = vim.fn.getcwd() }, { bufnr = buf })
    return
  end
  if client_id == nil or vim.lsp.get_client_by_id(client_id) == nil then
    client_id = vim.lsp.start_client({ name = 'tsfc', cmd = cmd, root_dir = vim.fn.getcwd() })
  end
  if client_id then
    vim.lsp.buf_attach_client(buf, client_id)
  end
end

local function format(buf)
  if vim.lsp.buf.format then -- Neovim 0.8+
    vim.lsp.buf.format({ bufnr = buf, name = 'tsfc', timeout_ms = 2000 })
  else
    vim.lsp.buf.formatting_sync(nil, 2000)
  end
end

function M.setup(opts)
  opts = opts or {}
  local cmd = opts.cmd or { 'tsfc', 'lsp' }
  vim.filetype.add({ extension = { tsf = 'tsf' } })
  local group = vim.api.nvim_create_augroup('tsfc', { clear = true })
  vim.api.nvim_create_autocmd('FileType', {
    group = group,
    pattern = 'tsf',
    callback = function(args)
      vim.bo[args.buf].commentstring = '// %s'
      attach(args.buf, cmd)
    end,
  })
  if opts.format_on_save ~= false then
    vim.api.nvim_create_autocmd('BufWritePre', {
      group = group,
      pattern = '*.tsf',
      callback = function(args)
        format(args.buf)
      end,
    })
  end
end

return M
