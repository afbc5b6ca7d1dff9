// Speech sound in sync with the face (mien.server.speech).
//
// The server starts an utterance on a tick and announces it on the stream as a text message
// {"speech": {"id", "character", "url", "start_s", "duration_s", "text"}}: start_s is on the clock the binary
// frames carry (time_s). The page shows each frame as it arrives, so the frame of server time t shows at about
// t + offset on the page's clock, where offset = min over frames of (arrival - time_s) (the least-delayed frame).
// The sound is scheduled on a Web Audio context so that its sample at s seconds is heard at
// start_s + s + offset + a playout delay (PLAYOUT_DELAY_S, more while frames come late), and while it plays
// the page shows the received frame of the sound's time (frameAt) instead of the newest: the face follows the
// sound, and a frame that arrives up to the delay late (a busy page, a slow renderer, a jittery network) still
// shows on time. A viewer that joins mid-sentence skips into the sound.

/** Least seconds the face and sound run behind the stream while a sound plays. */
export const PLAYOUT_DELAY_S = 0.15;
/** Most seconds: a page whose frames come later than this shows them late rather than lag further. */
export const MAX_PLAYOUT_DELAY_S = 0.5;

/**
 * The frame of `frames` (oldest first, each with timeS) to show at server time `timeS`: the newest one not
 * more than half a 60 Hz tick after it (null: none that old).
 */
export function frameAt(frames, timeS) {
  for (let i = frames.length - 1; i >= 0; i--) {
    if (frames[i].timeS <= timeS + 1 / 120) return frames[i];
  }
  return null;
}

/**
 * When to start a sound whose first sample belongs to server time startS: { when, skip } in the audio
 * context's seconds (start at `when`, `skip` seconds into the sound). `offsetS`: page clock - server clock;
 * `nowS`: the page clock now (seconds); `contextS`: the audio context's currentTime now; `latencyS`: the
 * output latency (a sample scheduled at `when` is heard latencyS later).
 */
export function scheduleStart(startS, offsetS, nowS, contextS, latencyS = 0) {
  const when = contextS + (startS + offsetS - nowS) - latencyS;
  if (when >= contextS) return { when, skip: 0 };
  return { when: contextS, skip: contextS - when };
}

export class SpeechPlayer {
  /**
   * `fetchSound(url)` resolves to the WAV's ArrayBuffer; `now()` is the page clock in seconds.
   */
  constructor(fetchSound, now = () => performance.now() / 1000) {
    this.fetchSound = fetchSound;
    this.now = now;
    this.context = null;
    this.enabled = true;
    this.offsetS = null; // page clock - server clock, from the least-delayed frame
    this.lateness = []; // seconds each of the last 120 frames came after the least-delayed one
    this.current = null; // { id, startS, durationS, source, when, skip, text }
    this.played = 0;
  }

  /** Create or resume the audio context (browsers allow it after a user gesture). */
  unlock() {
    if (!this.context) this.context = new AudioContext();
    if (this.context.state === "suspended") this.context.resume();
    return this.context;
  }

  /** A frame of server time `timeS` arrived now. */
  noteFrame(timeS) {
    const offset = this.now() - timeS;
    if (this.offsetS === null || offset < this.offsetS) this.offsetS = offset;
    this.lateness.push(offset - this.offsetS);
    if (this.lateness.length > 120) this.lateness.shift();
  }

  /** The playout delay: the latest of the last 2 s of frames plus a tick, within the two bounds (seconds). */
  delayS() {
    const latest = this.lateness.length ? Math.max(...this.lateness) : 0;
    return Math.min(MAX_PLAYOUT_DELAY_S, Math.max(PLAYOUT_DELAY_S, latest + 1 / 60));
  }

  /** The stream (re)connected: the server's clock may have started again. */
  resetClock() {
    this.offsetS = null;
    this.lateness = [];
    this.stop();
  }

  stop() {
    if (this.current && this.current.source) {
      try {
        this.current.source.stop();
      } catch {
        // already stopped
      }
    }
    this.current = null;
  }

  /** Play an announced utterance in step with the frames; resolves to a status line. */
  async play(speech) {
    this.stop();
    const entry = { id: speech.id, startS: speech.start_s, durationS: speech.duration_s, text: speech.text, source: null };
    this.current = entry;
    if (!this.enabled) return `says "${speech.text}" (sound off)`;
    const context = this.unlock();
    const data = await this.fetchSound(speech.url);
    const buffer = await context.decodeAudioData(data);
    if (this.current !== entry) return null; // a newer utterance replaced it meanwhile
    if (this.offsetS === null) return `says "${speech.text}" (no frame yet to time its sound)`;
    const latency = context.outputLatency || context.baseLatency || 0;
    const { when, skip } = scheduleStart(entry.startS, this.offsetS + this.delayS(), this.now(), context.currentTime, latency);
    if (skip >= buffer.duration) return `says "${speech.text}" (its sound has ended)`;
    const source = context.createBufferSource();
    source.buffer = buffer;
    source.connect(context.destination);
    source.start(when, skip);
    Object.assign(entry, { source, when, skip, latency });
    source.onended = () => {
      if (this.current === entry) this.current = null;
    };
    this.played += 1;
    return context.state === "running" ? `says "${speech.text}"` : `says "${speech.text}" (click the page for sound)`;
  }

  /** Server time of the sample heard now (null: no sound playing). */
  soundTimeS() {
    const entry = this.current;
    if (!entry || !entry.source || !this.context) return null;
    const heard = this.context.currentTime - entry.latency - entry.when;
    if (heard < 0) return null;
    return entry.startS + entry.skip + heard;
  }
}
