// A measured record chosen on disk for a study's form (a calibration's, a signal match's): read when
// chosen, described under its input, its problems named in the form's box.
import { $, showProblems } from "./dom.js";

// Watch the file input `input`: `parse(text)` reads a file's shape into {record, lines} (throwing
// [{field, message}] when it cannot), `described(record)` says what was read, `unreadable(name)`
// titles the problems of a file that is not a record. Returns `chosen`: `chosen.measured`, the
// record read (or null), and `chosen.line(field)`, which names a refused sample, `record.time[5]`,
// also by its line in the file.
export function chooseRecordFile({ input, info, box, parse, described, unreadable }) {
  const chosen = { measured: null };
  chosen.line = (field) => {
    const match = /^record\.\w+\[(\d+)\]$/.exec(field);
    const line = match && chosen.measured ? chosen.measured.lines[Number(match[1])] : undefined;
    return line === undefined ? field : `${field} (line ${line})`;
  };
  $(input).addEventListener("change", async () => {
    const file = $(input).files[0];
    chosen.measured = null;
    if (!file) return;
    try {
      chosen.measured = parse(await file.text());
      showProblems($(box), null);
      $(info).textContent = `${file.name}: ${described(chosen.measured.record)}.`;
    } catch (problems) {
      if (!Array.isArray(problems)) throw problems;
      $(info).textContent = "";
      showProblems($(box), unreadable(file.name), problems, "where");
    }
  });
  return chosen;
}
