-- Argo CD health of a simtest.dev TestCampaign (resource.customizations.health.simtest.dev_TestCampaign).
-- Healthy: the Complete condition is True and the phase is Succeeded.
-- Degraded: the phase is Failed or Error (a criterion was violated, or the infrastructure broke),
--   or Cancelled (the campaign will never complete).
-- Suspended: spec.suspend paused it (phase Suspended).
-- Progressing: everything else, including a status the operator computed for an older spec.
-- Lua 5.1 (gopher-lua), as Argo CD runs it; tests/packaging/test_argocd.py runs it with lupa.
local hs = {}
local status = obj.status
if status == nil then
  hs.status = "Progressing"
  hs.message = "Waiting for the simtest operator"
  return hs
end

local function counters()
  return string.format("%s done: %d passed, %d failed, %d errored, %d timed out, %d invalid",
    status.progress or "0/0", status.passed or 0, status.failed or 0, status.errored or 0,
    status.timedOut or 0, status.invalid or 0)
end

local generation = obj.metadata and obj.metadata.generation
if generation ~= nil and status.observedGeneration ~= nil and status.observedGeneration < generation then
  hs.status = "Progressing"
  hs.message = "The operator has not observed generation " .. generation .. " yet"
  return hs
end

local complete = nil
if status.conditions ~= nil then
  for _, condition in ipairs(status.conditions) do
    if condition.type == "Complete" then
      complete = condition
    end
  end
end

local phase = status.phase
if phase == "Failed" or phase == "Error" or phase == "Cancelled" then
  hs.status = "Degraded"
  local reason = ""
  if complete ~= nil and complete.message ~= nil and complete.message ~= "" then
    reason = ": " .. complete.message
  end
  hs.message = phase .. reason .. " (" .. counters() .. ")"
  return hs
end
if phase == "Succeeded" and complete ~= nil and complete.status == "True" then
  hs.status = "Healthy"
  hs.message = counters()
  return hs
end
if phase == "Suspended" then
  hs.status = "Suspended"
  hs.message = "Suspended (" .. counters() .. ")"
  return hs
end
hs.status = "Progressing"
hs.message = (phase or "Pending") .. " (" .. counters() .. ")"
return hs
