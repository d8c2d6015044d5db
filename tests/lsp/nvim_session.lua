-- A real editor session against `tsfc lsp`, run by tests/tests/lsp_nvim.rs:
--   nvim --headless --clean -c "luafile tests/lsp/nvim_session.lua"
-- The plan (a JSON file named by TSFC_LSP_PLAN) gives the server binary, the
-- spec (with a mistake), the places to hover and jump from, the fix and the
-- file to write the findings to. Every wait is bounded; the Rust test asserts
-- on the findings. Works with Neovim 0.7 (Debian bookworm) and later.

local plan = vim.fn.json_decode(vim.fn.readfile(os.getenv("TSFC_LSP_PLAN")))
local found = { nvim = tostring(vim.version().major) .. "." .. tostring(vim.version().minor) .. "." .. tostring(vim.version().patch) }
local WAIT = 15000

local function finish()
  vim.fn.writefile({ vim.fn.json_encode(found) }, plan.out)
  vim.cmd("qa!")
end

local ok, err = pcall(function()
  vim.cmd("edit " .. vim.fn.fnameescape(plan.spec))
  local buf = vim.api.nvim_get_current_buf()
  local client = vim.lsp.start_client({
    name = "tsfc",
    cmd = { plan.tsfc, "lsp" },
    root_dir = vim.fn.fnamemodify(plan.spec, ":h"),
    flags = { debounce_text_changes = 20 },
  })
  found.client = client ~= nil
  vim.lsp.buf_attach_client(buf, client)

  local function diagnostics()
    local out = {}
    for _, d in ipairs(vim.diagnostic.get(buf)) do
      table.insert(out, { line = d.lnum, col = d.col, end_line = d.end_lnum, end_col = d.end_col,
        severity = d.severity, message = d.message })
    end
    return out
  end

  -- The hover text (Markdown) at a 0-based line and byte column.
  local function hover(at)
    vim.api.nvim_win_set_cursor(0, { at[1] + 1, at[2] })
    local params = vim.lsp.util.make_position_params()
    local res = vim.lsp.buf_request_sync(buf, "textDocument/hover", params, WAIT)
    for _, r in pairs(res or {}) do
      if r.result and r.result.contents then
        return r.result.contents.value or vim.inspect(r.result.contents)
      end
      if r.err then return "error: " .. vim.inspect(r.err) end
    end
    return vim.NIL
  end

  found.opened_diagnostics = vim.wait(WAIT, function() return #vim.diagnostic.get(buf) > 0 end, 20)
  found.diagnostics = diagnostics()
  found.hover_const_broken = hover(plan.hover_const_decl)

  -- Fix the mistake: a buffer edit, sent to the server as didChange.
  vim.api.nvim_buf_set_lines(buf, plan.fix_line, plan.fix_line + 1, false, { plan.fix_text })
  found.cleared = vim.wait(WAIT, function() return #vim.diagnostic.get(buf) == 0 end, 20)
  found.diagnostics_after_fix = diagnostics()

  found.hover_const = hover(plan.hover_const)
  found.hover_set = hover(plan.hover_set)

  -- Go to definition as a user does it: the cursor jumps to the declaration.
  vim.api.nvim_win_set_cursor(0, { plan.definition_from[1] + 1, plan.definition_from[2] })
  vim.lsp.buf.definition()
  vim.wait(WAIT, function() return vim.api.nvim_win_get_cursor(0)[1] ~= plan.definition_from[1] + 1 end, 20)
  local cur = vim.api.nvim_win_get_cursor(0)
  found.definition = { cur[1] - 1, cur[2] }

  -- Formatting through the server (Neovim 0.7: formatting_sync; later: format).
  local before = table.concat(vim.api.nvim_buf_get_lines(buf, 0, -1, false), "\n")
  local fok, ferr = pcall(function()
    if vim.lsp.buf.format then
      vim.lsp.buf.format({ bufnr = buf, timeout_ms = WAIT })
    else
      vim.lsp.buf.formatting_sync(nil, WAIT)
    end
  end)
  found.format_error = fok and vim.NIL or tostring(ferr)
  found.formatted = table.concat(vim.api.nvim_buf_get_lines(buf, 0, -1, false), "\n") .. "\n"
  found.format_changed = found.formatted ~= before .. "\n"

  vim.lsp.stop_client(client)
end)

if not ok then found.error = tostring(err) end
finish()
