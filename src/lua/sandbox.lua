-- The Lua half of caustic's scene sandbox (sandbox.rs): `io`, `require`, `package`, `dofile` and
-- `loadfile` over the Rust functions that read files in the scene's folders. Called with
-- (write, read_scene_file, find_scene_module); returns the `io` table.
local write, read_scene_file, find_scene_module = ...
local load, error, type, tostring, select, setmetatable = load, error, type, tostring, select, setmetatable
local find, sub, tonumber = string.find, string.sub, tonumber

local File = {}
File.__index = File
File.__name = "FILE*"
function File:close() self.closed = true return true end
function File:seek(whence, offset)
  whence, offset = whence or "cur", offset or 0
  local base = (whence == "set" and 0) or (whence == "end" and #self.data) or (self.pos - 1)
  self.pos = base + offset + 1
  return self.pos - 1
end
local function read_one(self, fmt)
  local data, pos = self.data, self.pos
  if type(fmt) == "number" then
    if pos > #data then return nil end
    self.pos = pos + fmt
    return sub(data, pos, pos + fmt - 1)
  end
  fmt = tostring(fmt):gsub("^%*", "")
  local c = sub(fmt, 1, 1)
  if c == "a" then self.pos = #data + 1 return sub(data, pos) end
  if pos > #data then return nil end
  if c == "l" or c == "L" then
    local e = find(data, "\n", pos, true)
    local line = sub(data, pos, (e or #data + 1) - 1)
    self.pos = (e or #data) + 1
    if c == "L" and e then line = line .. "\n" end
    return line
  end
  if c == "n" then
    local s, e = find(data, "^%s*[-+]?[%w%.]+", pos)
    if not s then return nil end
    local cut = sub(data, s, e)
    local n = tonumber(cut)
    while not n and e > s do e = e - 1 cut = sub(data, s, e) n = tonumber(cut) end
    if n then self.pos = e + 1 end
    return n
  end
  error("bad argument to 'read' (invalid format)", 3)
end
function File:read(...)
  if self.closed then error("attempt to use a closed file", 2) end
  local n = select("#", ...)
  if n == 0 then return read_one(self, "l") end
  local out = {}
  for i = 1, n do
    local v = read_one(self, (select(i, ...)))
    out[i] = v
    if v == nil then return table.unpack(out, 1, i) end
  end
  return table.unpack(out, 1, n)
end
function File:lines(...)
  local fmts = table.pack(...)
  return function()
    if fmts.n == 0 then return self:read() end
    return self:read(table.unpack(fmts, 1, fmts.n))
  end
end
function File:write() error("this file was opened for reading: scene scripts cannot write files", 2) end

local io = {}
function io.open(path, mode)
  mode = mode or "r"
  if mode ~= "r" and mode ~= "rb" then
    error("io.open(" .. tostring(path) .. ", '" .. tostring(mode) .. "'): scene scripts may only " ..
      "read files (mode 'r'); caustic runs scenes in a sandbox (docs/security.md)", 2)
  end
  local data, err = read_scene_file(path)
  if not data then return nil, err, 2 end
  return setmetatable({data = data, pos = 1}, File)
end
function io.lines(path, ...)
  if path == nil then error("io.lines() reads standard input, which scene scripts cannot", 2) end
  local f, err = io.open(path)
  if not f then error(err, 2) end
  local it = f:lines(...)
  return function()
    local v = it()
    if v == nil then f:close() end
    return v
  end
end
io.write = function(...) write(...) return io end
io.type = function(f) if getmetatable(f) == File then return f.closed and "closed file" or "file" end return nil end

function loadfile(path, mode, ...)
  local data, name = read_scene_file(path)
  if not data then return nil, name end
  if select("#", ...) > 0 then return load(data, name, "t", (...)) end
  return load(data, name, "t")
end
function dofile(path)
  local f, err = loadfile(path)
  if not f then error(err, 2) end
  return f()
end

local loaded = {_G = _G, string = string, table = table, math = math, utf8 = utf8,
                coroutine = coroutine, os = os, io = io, debug = debug}
package = {loaded = loaded, preload = {}, searchers = {}}
package.searchers[1] = function(name)
  local f = package.preload[name]
  if f then return f, ":preload:" end
  return "\n\tno field package.preload['" .. name .. "']"
end
package.searchers[2] = find_scene_module
loaded.package = package
function require(name)
  if type(name) ~= "string" then
    error("bad argument #1 to 'require' (string expected, got " .. type(name) .. ")", 2)
  end
  local have = loaded[name]
  if have ~= nil then return have end
  local why = ""
  for _, searcher in ipairs(package.searchers) do
    local loader, extra = searcher(name)
    if type(loader) == "function" then
      local v = loader(name, extra)
      if v == nil then v = loaded[name] end
      if v == nil then v = true end
      loaded[name] = v
      return v, extra
    elseif type(loader) == "string" then
      why = why .. loader
    end
  end
  error("module '" .. name .. "' not found:" .. why, 2)
end
-- Two library loops that run in C, where the time budget's hook never fires, with counts
-- only a hostile script asks for: string.rep of an empty string (no memory is taken, so the
-- memory limit never stops it) and table.move of nils.
local rep, move = string.rep, table.move
string.rep = function(s, n, sep)
  if type(n) == "number" and n > 2^31 and #tostring(s) + #tostring(sep or "") == 0 then
    return ""
  end
  return rep(s, n, sep)
end
table.move = function(a1, f, e, t, a2)
  if type(f) == "number" and type(e) == "number" and e - f >= 2^27 then
    error("table.move: " .. string.format("%.0f", e - f + 1) .. " elements is more than a " ..
      "scene script may move at once (2^27); caustic runs scenes in a sandbox (docs/security.md)", 2)
  end
  return move(a1, f, e, t, a2)
end
return io
